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
};

}  // namespace mpm
