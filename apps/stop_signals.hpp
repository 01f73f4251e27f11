// SIGINT and SIGTERM while a command works: a flag its loop reads between frames, so that it can
// stop cleanly (a run writes a checkpoint; a calibration says that nothing was kept).
#pragma once

#include <signal.h>

#include <csignal>

#include "core/process.hpp"

namespace sandflow {

/// The signal that asked the command to stop, 0 while none has.
inline volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" inline void on_stop_signal(int sig) {
  g_stop_signal = sig;
}

/// For its lifetime, SIGINT and SIGTERM set g_stop_signal; a second one has the default effect
/// (SA_RESETHAND): the process ends at once. Nested (report around each render), only the
/// outermost installs and clears: an inner one that cleared the flag, or left a gap between two,
/// lost the signal (the report rendered on, or died of it without a word).
class StopSignals {
 public:
  StopSignals() : outermost_(depth()++ == 0) {
    if (!outermost_) return;
    g_stop_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART | SA_RESETHAND;
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~StopSignals() {
    if (--depth() > 0) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  /// Whether no other command's handlers were in place: a nested command (a render inside a
  /// report) leaves saying that it was interrupted to the one around it.
  bool outermost() const { return outermost_; }

 private:
  static int& depth() {
    static int d = 0;  // (made and ended on the main thread only)
    return d;
  }
  bool outermost_;
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

/// For its lifetime, the programs the command starts (POV-Ray, ffmpeg) are ended when a stop
/// signal comes (core/process.hpp), not waited for nor left running.
class StopChildren {
 public:
  StopChildren() { stop_children_on(&g_stop_signal); }
  ~StopChildren() { stop_children_on(nullptr); }
  StopChildren(const StopChildren&) = delete;
  StopChildren& operator=(const StopChildren&) = delete;
};

}  // namespace sandflow
