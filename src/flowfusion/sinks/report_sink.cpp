#include "flowfusion/sinks/report_sink.h"

#include "flowfusion/core/error.h"

namespace ff {

ReportSink::ReportSink(report::ReportOptions options) : options_(std::move(options)) {}

void ReportSink::end(RunSummary& summary, const StaticMap*) {
  try {
    summary.written.push_back(report::writeReport(options_));
  } catch (const InputError& e) {
    summary.notes.push_back(std::string("no report written: ") + e.what());
  }
}

}  // namespace ff
