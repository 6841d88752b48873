#pragma once
// Output folders that never touch the user's data: an output folder may not be, contain or lie
// inside an input, and --overwrite removes exactly the files a previous flowfusion command wrote
// there, as listed in the folder's manifest (.flowfusion-manifest, one relative path per line,
// appended as each file is written through core/atomic_file.h, so an interrupted command's files
// are listed too), and nothing else. A command holds its output folder locked (flock on the folder
// itself) from prepareOutputDir until it releases it or exits, so two commands never write into one
// folder at once.
#include <string>

namespace ff {

inline constexpr const char* kManifestName = ".flowfusion-manifest";

// Names the command whose output prepareOutputDir prepares ("run", "synth"): the manifest records
// it, and --overwrite replaces only the output of the same command. Executables set it once.
void setOutputCommand(const std::string& command);

// Makes `dir` ready for results and starts listing the files written under it in its manifest.
// A missing folder is created; an empty one is accepted; a non-empty one is an InputError unless
// `overwrite` is set, and then the files its manifest lists are removed (with folders they leave
// empty) while everything else stays (a folder without a manifest keeps all its files; those the
// command writes again are replaced). A manifest written by another command is an InputError.
// The folder is locked first: one another process holds is an InputError (the process keeps the
// lock until releaseOutputDir(), the next prepareOutputDir() of another folder, or its exit).
void prepareOutputDir(const std::string& dir, bool overwrite);

// Ends the output of the folder prepareOutputDir prepared last: its writes are no longer listed
// and its lock is released (for a library user who writes several outputs in one process).
void releaseOutputDir();

// For a command that failed before writing anything worth keeping: removes what it wrote into
// the folder prepareOutputDir prepared last (the files its manifest lists, the folders they leave
// empty, the manifest), and the folder itself when prepareOutputDir created it and it is left
// empty, so that the failure leaves nothing that blocks a rerun; then releases it.
void abandonOutputDir();

// InputError when the output folder is, contains or lies inside `input` (a folder or a file;
// `what` names it, e.g. "the input sequence"), compared after resolving links, "." and "..".
void refuseOverlap(const std::string& out_dir, const std::string& input, const std::string& what);

namespace detail {
// Called by the atomic writer before a file is renamed into place: lists `path` in the manifest
// of the folder prepareOutputDir prepared last, when it lies inside that folder.
void recordOutputFile(const std::string& path);
}  // namespace detail

}  // namespace ff
