// The pipeline: assembly checks, insertion and replacement by name, the stages' diagnostics,
// and the one step loop (mpm::advance).
#include <mpm/core/advance.h>
#include <mpm/core/pipeline.h>

#include <doctest/doctest.h>

#include <memory>
#include <string>
#include <vector>

namespace {

struct Clock {
  double time = 0.0, dt = 0.0, dt_limit = 1e300;
  long step = 0;
  std::vector<std::string> log;
};

class Named final : public mpm::Stage<Clock> {
public:
  Named(std::string name, std::vector<std::string> reads, std::vector<std::string> writes, double dt = 0.0,
        std::vector<mpm::Diagnostic> diagnostics = {})
      : name_(std::move(name)),
        reads_(std::move(reads)),
        writes_(std::move(writes)),
        dt_(dt),
        diagnostics_(std::move(diagnostics)) {}
  std::string name() const override { return name_; }
  std::vector<std::string> reads() const override { return reads_; }
  std::vector<std::string> writes() const override { return writes_; }
  void run(Clock& c) override {
    c.log.push_back(name_);
    if (dt_ != 0.0) c.dt = std::min(dt_, c.dt_limit);
  }
  std::vector<mpm::Diagnostic> diagnostics() const override { return diagnostics_; }

private:
  std::string name_;
  std::vector<std::string> reads_, writes_;
  double dt_;
  std::vector<mpm::Diagnostic> diagnostics_;
};

std::unique_ptr<Named> stage(std::string name, std::vector<std::string> reads, std::vector<std::string> writes) {
  return std::make_unique<Named>(std::move(name), std::move(reads), std::move(writes));
}

}  // namespace

TEST_CASE("a stage reading a field nobody wrote is refused at assembly") {
  mpm::Pipeline<Clock> p({"a"});
  p.add(stage("first", {"a"}, {"b"}));
  CHECK_THROWS_WITH_AS(p.add(stage("second", {"c"}, {})),
                       "pipeline: stage 'second' reads field 'c' that no earlier stage writes and the scene does not "
                       "provide",
                       mpm::InputError);
  CHECK(p.stage_names() == std::vector<std::string>{"first"});
}

TEST_CASE("stages are inserted and replaced by name; a change that breaks the order is undone") {
  mpm::Pipeline<Clock> p({"a"});
  p.add(stage("first", {"a"}, {"b"})).add(stage("last", {"b"}, {}));
  p.insert_after("first", stage("middle", {"b"}, {"c"}));
  p.insert_before("first", stage("zeroth", {"a"}, {}));
  CHECK(p.stage_names() == std::vector<std::string>{"zeroth", "first", "middle", "last"});
  p.replace("last", stage("final", {"c"}, {}));
  CHECK(p.stage_names() == std::vector<std::string>{"zeroth", "first", "middle", "final"});
  CHECK_THROWS_AS(p.replace("first", stage("other", {"a"}, {})), mpm::InputError);  // middle reads b
  CHECK_THROWS_AS(p.insert_before("first", stage("early", {"c"}, {})), mpm::InputError);
  CHECK_THROWS_WITH_AS(p.insert_after("missing", stage("x", {}, {})),
                       "pipeline: no stage 'missing' (stages: zeroth, first, middle, final)", mpm::InputError);
  CHECK(p.stage_names() == std::vector<std::string>{"zeroth", "first", "middle", "final"});
  Clock c;
  p.step(c);
  CHECK(c.log == std::vector<std::string>{"zeroth", "first", "middle", "final"});
  CHECK(p.times().names == p.stage_names());
}

TEST_CASE("diagnostics of equal names add up, in pipeline order") {
  mpm::Pipeline<Clock> p({});
  p.add(std::make_unique<Named>("source1", std::vector<std::string>{}, std::vector<std::string>{}, 0.0,
                                std::vector<mpm::Diagnostic>{{"inflow_mass", 2.0, true}}));
  p.add(std::make_unique<Named>("solve", std::vector<std::string>{}, std::vector<std::string>{}, 0.0,
                                std::vector<mpm::Diagnostic>{{"iterations", 7.0}}));
  p.add(std::make_unique<Named>("source2", std::vector<std::string>{}, std::vector<std::string>{}, 0.0,
                                std::vector<mpm::Diagnostic>{{"inflow_mass", 3.0, true}}));
  const auto d = p.diagnostics();
  REQUIRE(d.size() == 2);
  CHECK(d[0].name == "inflow_mass");
  CHECK(d[0].value == 5.0);
  CHECK(d[1].name == "iterations");
}

TEST_CASE("advance lands exactly on the target time and stops a collapsed step") {
  mpm::Pipeline<Clock> p({});
  p.add(std::make_unique<Named>("time_step", std::vector<std::string>{}, std::vector<std::string>{"dt"}, 0.3));
  Clock c;
  mpm::advance(c, p, 1.0);
  CHECK(c.time == 1.0);  // 0.3, 0.6, 0.9, then the clipped 0.1
  CHECK(c.step == 4);
  mpm::Pipeline<Clock> stuck({});
  stuck.add(std::make_unique<Named>("time_step", std::vector<std::string>{}, std::vector<std::string>{"dt"}, 1e-9));
  Clock d;
  CHECK_THROWS_AS(mpm::advance(d, stuck, 1.0, 100), mpm::NumericalError);
  CHECK(d.step == 101);  // the step that overran is taken, then refused
}
