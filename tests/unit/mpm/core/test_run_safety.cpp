// Run safety: the memory estimate refuses what does not fit, seeding asks it before it
// allocates, and the stop signals are recorded (not fatal) while a StopSignals lives, restored
// after it, and stop advance() after the current step.
#include <mpm/core/advance.h>
#include <mpm/core/error.h>
#include <mpm/core/memory_budget.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/stop_signals.h>
#include <mpm/geometry/seeding.h>

#include <doctest/doctest.h>

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <memory>
#include <string>

#include <signal.h>

namespace {

//! The smallest state and pipeline advance() needs: one stage that takes a fixed step.
struct ClockState {
  double time = 0.0, dt = 0.0, dt_limit = 0.0;
  std::int64_t step = 0;
};

class FixedStep : public mpm::Stage<ClockState> {
public:
  std::string name() const override { return "time_step"; }
  std::vector<std::string> reads() const override { return {}; }
  std::vector<std::string> writes() const override { return {"dt"}; }
  void run(ClockState& s) override { s.dt = std::min(0.1, s.dt_limit); }
};

}  // namespace

TEST_CASE("the memory estimate refuses what exceeds the available memory or the cap") {
  CHECK(mpm::memory_shortfall(1e6).empty());
  const std::string huge = mpm::memory_shortfall(1e18);
  CHECK(huge.find("1e+09 GB") != std::string::npos);
  CHECK(huge.find("MemAvailable") != std::string::npos);
  // Seeding asks before it allocates: 10^9 lattice points (450 GB) are refused with the estimate.
  CHECK_THROWS_WITH_AS(mpm::geometry::seed_box<3>(mpm::Vec<3>::Zero(), mpm::Vec<3>::Ones(), 1e-3, 1, 0.0, 1),
                       doctest::Contains("particles at grid spacing dx = 0.001 m"), mpm::InputError);
  mpm::cap_memory(1.0);  // one byte: less than this process holds
  CHECK(mpm::memory_shortfall(1.0).find("of --max-memory") != std::string::npos);
  CHECK_THROWS_AS(mpm::geometry::seed_box<2>(mpm::Vec<2>::Zero(), mpm::Vec<2>::Ones(), 0.1, 4, 0.0, 1),
                  mpm::InputError);
}

TEST_CASE("SIGINT and SIGTERM are recorded while StopSignals lives and stop advance after the step") {
  struct sigaction before {};
  sigaction(SIGTERM, nullptr, &before);
  {
    const mpm::StopSignals signals;
    CHECK(mpm::StopSignals::received() == 0);
    std::raise(SIGTERM);  // would end the process without the handler
    CHECK(mpm::StopSignals::received() == SIGTERM);

    ClockState state;
    mpm::Pipeline<ClockState> pipeline({});
    pipeline.add(std::make_unique<FixedStep>());
    const bool reached = mpm::advance(state, pipeline, 1.0, 100, 0.0, [] { return mpm::StopSignals::received() != 0; });
    CHECK_FALSE(reached);
    CHECK(state.step == 1);  // the step in progress finished, no more
    CHECK(state.time == doctest::Approx(0.1));
  }
  struct sigaction after {};
  sigaction(SIGTERM, nullptr, &after);
  CHECK(reinterpret_cast<void*>(after.sa_handler) == reinterpret_cast<void*>(before.sa_handler));
  {
    const mpm::StopSignals again;  // a new run starts with no signal recorded
    CHECK(mpm::StopSignals::received() == 0);
  }
}
