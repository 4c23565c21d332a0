#pragma once
//! Graceful stop of a run: while a StopSignals object lives, SIGINT (Ctrl-C) and SIGTERM (what a
//! batch scheduler sends before it kills a job) do not end the process; they are recorded, and
//! the run loop (Runner) finishes the step it is in, writes a checkpoint and throws
//! StopRequested, which the apps turn into exit code 128 + the signal number (130, 143), as a
//! shell reports a process ended by that signal. A second signal of the same kind, after the
//! first, ends the process at once (the default action is restored when the first arrives).
#include <mpm/core/error.h>

#include <string>

namespace mpm {

class StopSignals {
public:
  StopSignals();   //!< installs the handlers and clears an earlier record
  ~StopSignals();  //!< restores the handlers that were there before
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  //! The signal received since construction (SIGINT or SIGTERM), 0 when none.
  static int received();
};

//! Thrown by the run loop after it stopped on a signal and saved a checkpoint.
class StopRequested : public Error {
public:
  StopRequested(int signal, const std::string& message) : Error(message), signal_(signal) {}
  int signal() const { return signal_; }

private:
  int signal_;
};

}  // namespace mpm
