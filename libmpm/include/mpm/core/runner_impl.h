#pragma once
//! The definitions of mpm::Runner (runner.h). Public so that a library with its own state type
//! can instantiate the Runner for it: libmpm/src/core/runner.cpp does for MpmState, libcoupling
//! for CoupledState (`template class mpm::Runner<dim, MyState>;` in one translation unit, with a
//! `phases(MyState&)` found by argument-dependent lookup, state.h).
#include <mpm/core/advance.h>
#include <mpm/core/error.h>
#include <mpm/core/runner.h>
#include <mpm/io/atomic_file.h>
#include <mpm/io/cell_output.h>
#include <mpm/io/checkpoint.h>
#include <mpm/io/diagnostics_csv.h>
#include <mpm/io/particle_output.h>
#include <mpm/io/png_preview.h>
#include <mpm/io/summary_json.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>

namespace mpm {

namespace runner_detail {
inline std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

inline std::string numbered(const std::string& stem, int frame, const std::string& ext) {
  char name[64];
  std::snprintf(name, sizeof name, "%s_%04d%s", stem.c_str(), frame, ext.c_str());
  return name;
}

//! The particle series of a phase: "particles" for the unnamed phase of a single-phase state.
inline std::string series_stem(const std::string& phase) { return phase.empty() ? "particles" : phase; }

//! A per-phase diagnostics column: "name" for the unnamed phase, "name_<phase>" otherwise.
inline std::string phase_column(const std::string& name, const std::string& phase) {
  return phase.empty() ? name : name + "_" + phase;
}
}  // namespace runner_detail

template <int dim, class State>
Runner<dim, State>::Runner(std::string app_name, CommandLine command_line, const Config& scene,
                           const SceneSettings<dim>& settings)
    : app_(std::move(app_name)), cl_(std::move(command_line)), scene_(scene), settings_(settings), out_(cl_.out_dir) {}

template <int dim, class State>
std::vector<std::string> Runner<dim, State>::columns(State& state, const Pipeline<State>& pipeline) const {
  std::vector<std::string> c = {
      "frame", "time",       "dt",        "steps", "kinetic_energy", "elastic_energy", "gravity_potential",
      "mass",  "momentum_x", "momentum_y"};
  if (dim == 3) c.push_back("momentum_z");
  c.push_back("max_speed");
  const auto all = phases(state);
  if (all.size() > 1)
    for (const PhaseRef<dim>& phase : all) c.push_back(runner_detail::phase_column("mass", phase.name));
  for (const auto& [name, fn] : extra_) c.push_back(name);
  for (const Diagnostic& d : pipeline.diagnostics()) c.push_back(d.name);
  // A stage that runs twice in a step (e.g. a phase's boundary again after the projection)
  // gets its own column: seconds_<name>, seconds_<name>_2, ...
  std::map<std::string, int> runs;
  for (const auto& stage : pipeline.stage_names()) {
    const int k = ++runs[stage];
    c.push_back("seconds_" + stage + (k > 1 ? "_" + std::to_string(k) : ""));
  }
  // Columns are read back by name (restart, studies): a name added twice would hide one.
  std::set<std::string> unique;
  for (const std::string& name : c)
    if (!unique.insert(name).second) throw std::logic_error(app_ + ": diagnostics column '" + name + "' added twice");
  return c;
}

template <int dim, class State>
std::vector<double> Runner<dim, State>::history_or_zero(const std::string& column) const {
  const auto& all = csv_.columns();
  if (std::find(all.begin(), all.end(), column) != all.end()) return csv_.column(column);
  return std::vector<double>(csv_.column("frame").size(), 0.0);
}

template <int dim, class State>
std::string Runner<dim, State>::scene_digest() const {
  // FNV-1a over the resolved keys that determine the solution: time.end and output.* may
  // change between a run and its restart.
  std::uint64_t h = 1469598103934665603ull;
  for (const auto& [key, value] : scene_.resolved()) {
    if (key == "time.end" || key.rfind("output.", 0) == 0) continue;
    for (const char c : key + "=" + value + ";") h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

template <int dim, class State>
int Runner<dim, State>::open_output(State& state, Pipeline<State>& pipeline) {
  // Half-written files of a run that was killed in this folder (io/atomic_file.h).
  io::remove_stale_temporaries(out_);
  if (!cl_.restart) {
    std::filesystem::create_directories(out_);
    csv_.open(out_ / "diagnostics.csv", columns(state, pipeline));
    return 0;
  }
  verify<InputError>(std::filesystem::exists(out_ / "diagnostics.csv"),
                     "--restart continues a run in its output folder, but '" + out_.string() +
                         "' holds no diagnostics.csv: pass --out with the folder of the run that wrote '" +
                         *cl_.restart + "'");
  // Each phase's particles, as the scene built them, declare the channels the checkpoint must hold.
  io::CheckpointHeader header;
  for (const PhaseRef<dim>& phase : phases(state))
    io::load_checkpoint<dim>(*cl_.restart, header, *phase.particles, phase.name);
  verify<InputError>(header.dim == dim, "checkpoint '" + *cl_.restart + "' is " + std::to_string(header.dim) +
                                            "D, the scene is " + std::to_string(dim) + "D");
  verify<InputError>(header.scene_digest == scene_digest(),
                     "checkpoint '" + *cl_.restart + "' was written by another scene (digest " + header.scene_digest +
                         ", this scene " + scene_digest() +
                         "): a restart needs the same keys and values, except time.end and output.*");
  state.time = header.time;
  state.step = header.step;
  pipeline.restore(header.stage_data);
  csv_.open_for_restart(out_ / "diagnostics.csv", columns(state, pipeline), header.frame);
  const std::string first_series = runner_detail::series_stem(phases(state).front().name);
  for (int f = 0; f <= header.frame; ++f)
    if (std::filesystem::exists(out_ / io::particle_file_name(f, first_series)))
      frames_written_.emplace_back(f, f * settings_.frame_dt);
  return header.frame;
}

template <int dim, class State>
void Runner<dim, State>::append_diagnostics(State& state, int frame, const Pipeline<State>& pipeline) {
  double kinetic = 0, potential = 0, mass = 0, max_speed2 = 0;
  Vec<dim> momentum = Vec<dim>::Zero();
  std::vector<double> phase_mass;
  for (const PhaseRef<dim>& phase : phases(state)) {
    const Particles<dim>& P = *phase.particles;
    double m = 0;
    for (std::size_t p = 0; p < P.size(); ++p) {
      kinetic += 0.5 * P.mass[p] * P.v[p].squaredNorm();
      potential -= P.mass[p] * settings_.gravity.dot(P.x[p]);
      m += P.mass[p];
      momentum += P.mass[p] * P.v[p];
      max_speed2 = std::max(max_speed2, P.v[p].squaredNorm());
    }
    mass += m;
    phase_mass.push_back(m);
  }
  std::vector<double> r = {double(frame), state.time,
                           state.dt,      double(state.step - steps_at_last_frame_),
                           kinetic,       elastic_energy_ ? elastic_energy_(state) : 0.0,
                           potential,     mass};
  for (int a = 0; a < dim; ++a) r.push_back(momentum[a]);
  r.push_back(std::sqrt(max_speed2));
  if (phase_mass.size() > 1) r.insert(r.end(), phase_mass.begin(), phase_mass.end());
  for (const auto& [name, fn] : extra_) r.push_back(fn(state));
  for (const Diagnostic& d : pipeline.diagnostics()) r.push_back(d.value);
  const StageTimes& t = pipeline.times();
  for (std::size_t s = 0; s < t.seconds.size(); ++s) {
    r.push_back(t.seconds[s] - stage_seconds_at_last_frame_[s]);
    stage_seconds_at_last_frame_[s] = t.seconds[s];
  }
  steps_at_last_frame_ = state.step;
  csv_.append(r);
}

template <int dim, class State>
void Runner<dim, State>::run(State& state, Pipeline<State>& pipeline) {
  if (!cl_.quiet) {
    std::cerr << app_ << ": " << cl_.scene_file << " (" << dim << "D), resolved parameters:\n";
    for (const auto& [key, value] : scene_.resolved()) std::cerr << "  " << key << " = " << value << "\n";
  }
  start_ = std::chrono::steady_clock::now();
  const int first_frame = open_output(state, pipeline);
  stage_seconds_at_last_frame_.assign(pipeline.stage_names().size(), 0.0);
  steps_at_last_frame_ = state.step;
  if (!cl_.restart) {
    append_diagnostics(state, 0, pipeline);
    write_frame(state, 0);
  }

  const int frames = settings_.frame_count();
  for (int frame = first_frame + 1; frame <= frames; ++frame) {
    advance(state, pipeline, std::min(frame * settings_.frame_dt, settings_.end_time), settings_.max_steps_per_frame,
            1e-12 * settings_.frame_dt);
    append_diagnostics(state, frame, pipeline);
    write_frame(state, frame);
    const bool checkpoint =
        frame == frames || (settings_.output.checkpoint_every > 0 && frame % settings_.output.checkpoint_every == 0);
    if (checkpoint) {
      std::vector<io::CheckpointPhase<dim>> stored;
      for (const PhaseRef<dim>& phase : phases(state)) stored.push_back({phase.name, phase.particles});
      io::CheckpointHeader h{dim, frame, state.step, state.time, state.dt, scene_digest(), pipeline.carried()};
      io::save_checkpoint<dim>(out_ / runner_detail::numbered("checkpoint", frame, ".h5"), stored, h);
    }
    if (!cl_.quiet) progress(state, frame, frame == frames);
  }

  wall_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  stage_names_ = pipeline.stage_names();
  stage_table_ = pipeline.times().table();
  particle_count_ = grid_nodes_ = 0;
  memory_.clear();
  for (const PhaseRef<dim>& phase : phases(state)) {
    particle_count_ += phase.particles->size();
    const std::string prefix = phase.name.empty() ? "" : phase.name + ".";
    for (const auto& [name, bytes] : phase.particles->memory_per_field()) memory_.emplace_back(prefix + name, bytes);
    for (std::size_t n = 0; n < phase.grids.size(); ++n) {
      grid_nodes_ += phase.grids[n]->node_storage();
      const std::string level = phase.grids.size() > 1 ? "level" + std::to_string(n) + "." : "";
      for (const auto& [name, bytes] : phase.grids[n]->memory_per_field())
        memory_.emplace_back(prefix + level + name, bytes);
    }
  }
  std::cerr << "\n" << app_ << ": stages run, in order, with their total time\n" << stage_table_;
  std::cerr << "memory held per field (bytes)\n";
  for (const auto& [name, bytes] : memory_)
    if (bytes > 0) std::fprintf(stderr, "  %-31s %14zu\n", name.c_str(), bytes);
}

template <int dim, class State>
void Runner<dim, State>::write_frame(State& state, int frame) {
  const auto all = phases(state);
  if (settings_.output.particles) {
    frames_written_.emplace_back(frame, state.time);
    for (const PhaseRef<dim>& phase : all) {
      const std::string stem = runner_detail::series_stem(phase.name);
      io::write_particles(out_ / io::particle_file_name(frame, stem), *phase.particles, state.time, frame);
      io::write_time_series_xdmf(out_, frames_written_, stem);
    }
    if constexpr (requires { state.adaptive; })  // the leaves of an adaptive grid (io/cell_output.h)
      if (state.adaptive) {
        io::write_cells(out_ / io::particle_file_name(frame, "cells"), state.adaptive->tree(), state.time, frame);
        io::write_cells_time_series<dim>(out_, frames_written_);
      }
  }
  if (settings_.output.png) {
    io::PreviewOptions o;
    for (int a = 0; a < dim; ++a) {
      o.domain_lo[a] = settings_.domain_lo[a];
      o.domain_hi[a] = settings_.domain_hi[a];
    }
    o.width_px = settings_.output.png_width;
    o.color_by = settings_.output.color_by;
    // Splats about as wide as the particle spacing: the widest phase's, so that grains which
    // hold a small share of their particle's volume (a dilute suspension) stay visible.
    double spacing = 0.0;
    for (const PhaseRef<dim>& phase : all)
      if (!phase.particles->volume0.empty())
        spacing = std::max(spacing, std::pow(phase.particles->volume0[0], 1.0 / dim));
    const double radius = std::max(1.0, 0.6 * spacing * o.width_px / (o.domain_hi[0] - o.domain_lo[0]));
    std::vector<io::PreviewLayer<dim>> layers;
    for (const PhaseRef<dim>& phase : all) {
      io::PreviewLayer<dim> layer{phase.particles, std::nullopt, spacing > 0.0 ? radius : o.point_radius_px};
      if (!phase.coloured) layer.colour = io::Rgb{166, 206, 227};  // light blue, under the grains
      layers.push_back(layer);
    }
    io::write_png_preview<dim>(out_ / runner_detail::numbered("preview", frame, ".png"), layers, o);
  }
}

template <int dim, class State>
void Runner<dim, State>::progress(const State& state, int frame, bool last) const {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const int frames = settings_.frame_count();
  const double eta = elapsed / frame * (frames - frame);
  std::fprintf(stderr, "\r[%s] frame %d/%d  t = %.4g s  steps %lld  elapsed %.1f s  ETA %.1f s   %s", app_.c_str(),
               frame, frames, state.time, static_cast<long long>(state.step), elapsed, eta, last ? "\n" : "");
  std::fflush(stderr);
}

template <int dim, class State>
void Runner<dim, State>::write_summary(const std::vector<std::pair<std::string, double>>& results) const {
  std::vector<std::pair<std::string, std::string>> info = {{"app", app_},
                                                           {"scene_file", cl_.scene_file},
                                                           {"dim", std::to_string(dim)},
                                                           {"wall_seconds", std::to_string(wall_seconds_)}};
  std::string stages;
  for (const auto& s : stage_names_) stages += (stages.empty() ? "" : ",") + s;
  info.emplace_back("stages", stages);
  info.emplace_back("steps", std::to_string(steps_at_last_frame_));
  info.emplace_back("particles", std::to_string(particle_count_));
  info.emplace_back("grid_nodes", std::to_string(grid_nodes_));
  for (const auto& [name, bytes] : memory_) info.emplace_back("memory_bytes." + name, std::to_string(bytes));
  io::write_summary(out_ / "summary.json", results, scene_.resolved(), info);
}

}  // namespace mpm
