#pragma once
// The process's peak memory, for a run's summary (summary.json's peak_memory_mib) and `bench`.

namespace ff {

// Peak resident set size of this process so far (getrusage ru_maxrss), MiB.
double peakResidentMiB();

}  // namespace ff
