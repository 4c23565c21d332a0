#pragma once
//! An ordered list of stages that advances a State by one step and times every stage. Stages
//! are appended by the scene's assembler and may be inserted or replaced by name afterwards (a
//! user's extra stage, another solver for one step); every change re-checks that each field is
//! written before it is read.
#include <mpm/core/error.h>
#include <mpm/core/stage.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
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

  //! Appends a stage; InputError when it reads a field that is neither initial nor written by
  //! an earlier stage.
  Pipeline& add(std::unique_ptr<Stage<State>> stage) { return insert(stages_.size(), std::move(stage)); }
  //! Inserts a stage before / after the first stage called `name`, or replaces that stage; the
  //! whole order is checked again. InputError when no stage has that name.
  Pipeline& insert_before(const std::string& name, std::unique_ptr<Stage<State>> stage) {
    return insert(position(name), std::move(stage));
  }
  Pipeline& insert_after(const std::string& name, std::unique_ptr<Stage<State>> stage) {
    return insert(position(name) + 1, std::move(stage));
  }
  Pipeline& replace(const std::string& name, std::unique_ptr<Stage<State>> stage) {
    const std::size_t at = position(name);
    std::swap(stages_[at], stage);
    try {
      check();
    } catch (...) {
      std::swap(stages_[at], stage);  // the pipeline stays as it was
      throw;
    }
    times_.names[at] = stages_[at]->name();
    times_.seconds[at] = 0.0;
    return *this;
  }

  void step(State& state) {
    for (std::size_t s = 0; s < stages_.size(); ++s) {
      const auto start = std::chrono::steady_clock::now();
      stages_[s]->run(state);
      times_.seconds[s] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  }

  //! Stage::synchronize of every stage: after stepping, before the state is read.
  void synchronize(State& state) {
    for (auto& stage : stages_) stage->synchronize(state);
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

  //! The diagnostics of every stage in pipeline order; columns of the same name add up (two
  //! emitters of one phase report one inflow).
  std::vector<Diagnostic> diagnostics() const {
    std::vector<Diagnostic> all;
    for (const auto& s : stages_)
      for (const Diagnostic& d : s->diagnostics()) {
        auto same = std::find_if(all.begin(), all.end(), [&](const Diagnostic& e) { return e.name == d.name; });
        if (same == all.end())
          all.push_back(d);
        else
          same->value += d.value;
      }
    return all;
  }

private:
  std::string prefix(std::size_t s) const { return std::to_string(s) + "." + stages_[s]->name() + "/"; }

  std::size_t position(const std::string& name) const {
    for (std::size_t s = 0; s < stages_.size(); ++s)
      if (stages_[s]->name() == name) return s;
    std::string names;
    for (const auto& s : stages_) names += (names.empty() ? "" : ", ") + s->name();
    throw InputError("pipeline: no stage '" + name + "' (stages: " + names + ")");
  }

  Pipeline& insert(std::size_t at, std::unique_ptr<Stage<State>> stage) {
    stages_.insert(stages_.begin() + static_cast<std::ptrdiff_t>(at), std::move(stage));
    try {
      check();
    } catch (...) {
      stages_.erase(stages_.begin() + static_cast<std::ptrdiff_t>(at));
      throw;
    }
    times_.names.insert(times_.names.begin() + static_cast<std::ptrdiff_t>(at), stages_[at]->name());
    times_.seconds.insert(times_.seconds.begin() + static_cast<std::ptrdiff_t>(at), 0.0);
    return *this;
  }

  //! Every field a stage reads is initial or written by an earlier stage.
  void check() const {
    std::set<std::string> available(initial_.begin(), initial_.end());
    for (const auto& s : stages_) {
      for (const auto& f : s->reads())
        if (!available.count(f))
          throw InputError("pipeline: stage '" + s->name() + "' reads field '" + f +
                           "' that no earlier stage writes and the scene does not provide");
      for (const auto& f : s->writes()) available.insert(f);
    }
  }

  std::vector<std::string> initial_;
  std::vector<std::unique_ptr<Stage<State>>> stages_;
  StageTimes times_;
};

}  // namespace mpm
