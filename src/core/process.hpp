// Other programs (POV-Ray, ffmpeg): found on PATH and run to their end, their output in a log
// file. The one place in src/ that starts a child process (docs/style.md, "One way to do a
// thing"); io/pov_writer.cpp renders and encodes with it.
//
// The library runs with other threads (OpenMP, a render pool), so between fork and exec the child
// may only call async-signal-safe functions: everything it needs (the argument array, the log's
// descriptor) is made before the fork, and the child only redirects, changes folder and execs.
#pragma once

#include <csignal>
#include <cstdint>
#include <string>
#include <vector>

namespace sandflow {

/// From now on, run_logged ends its child (SIGTERM) once `*flag` is non-zero, and returns
/// "WHAT was stopped": a command asked to stop (SIGINT, SIGTERM: the flag its handler sets) does
/// not wait for a render of minutes, nor leave it running. nullptr: wait for the child's end.
void stop_children_on(const volatile std::sig_atomic_t* flag);

/// Full path of the executable `name` found on PATH, or "" when there is none.
std::string find_program(const std::string& name);

/// Runs args[0] (a full path) with `args` in `work_dir`, stdin from /dev/null, stdout and stderr
/// to `log_path` (created or emptied), and waits for it. Returns "" on exit status 0, else what
/// went wrong, naming the program `what`: "cannot start WHAT: REASON", "WHAT failed with exit
/// status N" (127: it could not be executed, 126: no `work_dir`), "WHAT was killed by signal N".
/// Throws OutputError when the log cannot be created. Safe to call from several threads at once:
/// the log is opened close-on-exec, so a child started by another thread does not hold it. The
/// child is killed if sandflow dies first (PR_SET_PDEATHSIG): none outlives it. `peak_bytes`, when
/// given, receives the most memory the child held (its resident high-water mark; 0 if unknown).
std::string run_logged(std::vector<std::string> args, const std::string& work_dir,
                       const std::string& log_path, const std::string& what,
                       std::int64_t* peak_bytes = nullptr);

}  // namespace sandflow
