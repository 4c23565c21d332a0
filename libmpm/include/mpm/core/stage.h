#pragma once
//! A stage is one step of the time-stepping algorithm over shared state: a small named unit
//! that declares the fields it reads and writes, so a pipeline can check at assembly that
//! every field is produced before it is read (a missing stage fails at start-up, not with a
//! NaN at step 300). Hot loops stay inside run(); there is one virtual call per stage per step.
#include <string>
#include <utility>
#include <vector>

namespace mpm {

//! Named arrays a stage carries from one step to the next besides the state (a solver's warm
//! start), so that a checkpoint can hold them and a restarted run continue bit for bit.
using CarriedData = std::vector<std::pair<std::string, std::vector<double>>>;

//! One diagnostics column a stage reports: its value after the last step of a frame.
struct Diagnostic {
  std::string name;
  double value = 0.0;
  //! A quantity of the particle phase the stage acts on (the mass an emitter added): in a state
  //! of several phases the column is "<name>_<phase>". Otherwise it belongs to the step (a
  //! solver's iterations) and keeps its name.
  bool per_phase = false;
};

template <class State>
class Stage {
public:
  virtual ~Stage() = default;
  virtual std::string name() const = 0;
  virtual std::vector<std::string> reads() const = 0;
  virtual std::vector<std::string> writes() const = 0;
  virtual void run(State& state) = 0;
  //! What run() left for the next step (default: nothing) and its restoration.
  virtual CarriedData carried() const { return {}; }
  virtual void restore(const CarriedData& /*data*/) {}
  //! The stage's diagnostics columns, the same names after every step (default: none); the
  //! Runner writes them to diagnostics.csv, so no app wires a stage's figures by hand.
  virtual std::vector<Diagnostic> diagnostics() const { return {}; }
  //! Brings `state` up to date where the stage keeps part of it elsewhere between steps (the
  //! CUDA step keeps the particles on the GPU); whoever reads the state after stepping (the
  //! Runner, for output, diagnostics and checkpoints) calls Pipeline::synchronize first.
  virtual void synchronize(State& /*state*/) {}
};

}  // namespace mpm
