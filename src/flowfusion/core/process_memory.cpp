#include "flowfusion/core/process_memory.h"

#include <sys/resource.h>

namespace ff {

double peakResidentMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  // Linux reports ru_maxrss in KiB.
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

}  // namespace ff
