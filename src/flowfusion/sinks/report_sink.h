#pragma once
// The result sink that writes report.html (report.h) when a run ends (`flowfusion run --report`).
// It reads what FilesSink wrote (masks, map points, trajectory: the page `flowfusion report RUN_DIR`
// makes, without keeping every mask in memory), so it goes after the FilesSink in the run's sinks.
#include "flowfusion/pipeline/result_sink.h"
#include "flowfusion/report/report.h"

namespace ff {

class ReportSink : public ResultSink {
 public:
  // options.run_dir: the FilesSink's output folder; options.sequence: the run's sequence folder.
  explicit ReportSink(report::ReportOptions options);
  // Writes the report and adds it to summary.written; a report that cannot be written becomes a
  // note (the run's own files are complete by then).
  void end(RunSummary& summary, const StaticMap* map) override;

 private:
  report::ReportOptions options_;
};

}  // namespace ff
