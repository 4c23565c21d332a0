#pragma once
//! An ordered list of stages that advances a State by one step and times every stage.
#include <mpm/core/error.h>
#include <mpm/core/stage.h>

#include <chrono>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace mpm {

//! Seconds spent per stage, in pipeline order.
struct StageTimes {
  std::vector<std::string> names;
  std::vector<double> seconds;
  //! Fixed-width table with shares of the total, for the end of a run.
  std::string table() const;
};

template <class State>
class Pipeline {
public:
  //! `initial_fields` are the fields a scene provides before the first stage runs.
  explicit Pipeline(std::vector<std::string> initial_fields) : initial_(std::move(initial_fields)) {}

  Pipeline& add(std::unique_ptr<Stage<State>> stage) {
    std::set<std::string> available(initial_.begin(), initial_.end());
    for (const auto& s : stages_)
      for (const auto& f : s->writes()) available.insert(f);
    for (const auto& f : stage->reads())
      if (!available.count(f))
        throw InputError("pipeline: stage '" + stage->name() + "' reads field '" + f +
                         "' that no earlier stage writes and the scene does not provide");
    times_.names.push_back(stage->name());
    times_.seconds.push_back(0.0);
    stages_.push_back(std::move(stage));
    return *this;
  }

  void step(State& state) {
    for (std::size_t s = 0; s < stages_.size(); ++s) {
      const auto start = std::chrono::steady_clock::now();
      stages_[s]->run(state);
      times_.seconds[s] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  }

  //! The carried data of every stage, each name prefixed "<stage index>.<stage name>/".
  CarriedData carried() const {
    CarriedData all;
    for (std::size_t s = 0; s < stages_.size(); ++s)
      for (auto& [name, values] : stages_[s]->carried()) all.emplace_back(prefix(s) + name, std::move(values));
    return all;
  }
  //! Hands every stage its entries of `all` (as carried() wrote them, prefix removed).
  void restore(const CarriedData& all) {
    for (std::size_t s = 0; s < stages_.size(); ++s) {
      CarriedData mine;
      for (const auto& [name, values] : all)
        if (name.rfind(prefix(s), 0) == 0) mine.emplace_back(name.substr(prefix(s).size()), values);
      stages_[s]->restore(mine);
    }
  }

  const StageTimes& times() const { return times_; }
  std::vector<std::string> stage_names() const { return times_.names; }
  template <class StageType>
  StageType* find() {
    const auto all = find_all<StageType>();
    return all.empty() ? nullptr : all.front();
  }
  //! Every stage of type StageType, in pipeline order.
  template <class StageType>
  std::vector<StageType*> find_all() {
    std::vector<StageType*> found;
    for (auto& s : stages_)
      if (auto* p = dynamic_cast<StageType*>(s.get())) found.push_back(p);
    return found;
  }

private:
  std::string prefix(std::size_t s) const { return std::to_string(s) + "." + stages_[s]->name() + "/"; }

  std::vector<std::string> initial_;
  std::vector<std::unique_ptr<Stage<State>>> stages_;
  StageTimes times_;
};

}  // namespace mpm
