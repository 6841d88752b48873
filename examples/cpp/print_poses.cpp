// Opens a TUM-layout sequence, runs the system on it and prints the poses (TUM format).
// Usage: print_poses SEQUENCE_FOLDER
#include <cstdio>
#include <exception>

#include "flowfusion/flowfusion.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s SEQUENCE_FOLDER\n", argv[0]);
    return 2;
  }
  try {
    const std::unique_ptr<ff::FrameSource> source = ff::openFrameSource(argv[1], ff::SequenceOptions{});
    ff::FlowFusionSystem system(ff::SystemConfig{}, source->camera());
    while (const std::optional<ff::RgbdFrame> frame = source->next()) {
      const ff::FrameResult r = system.process(*frame);
      const Eigen::Quaterniond q(r.T_world_cam.rotation());
      const Eigen::Vector3d t = r.T_world_cam.translation();
      std::printf("%.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", r.timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(),
                  q.w());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "print_poses: %s\n", e.what());
    return 1;
  }
  return 0;
}
