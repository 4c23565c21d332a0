#pragma once
//! The definitions of mpm::Runner (runner.h). Public so that a library with its own state type
//! can instantiate the Runner for it: libmpm/src/core/runner.cpp does for MpmState, libcoupling
//! for CoupledState (`template class mpm::Runner<dim, MyState>;` in one translation unit, with a
//! `phases(MyState&)` found by argument-dependent lookup, state.h).
#include <mpm/core/advance.h>
#include <mpm/core/app.h>
#include <mpm/core/error.h>
#include <mpm/core/runner.h>
#include <mpm/core/stop_signals.h>
#include <mpm/io/atomic_file.h>
#include <mpm/io/cell_output.h>
#include <mpm/io/checkpoint.h>
#include <mpm/io/checksum.h>
#include <mpm/io/diagnostics_csv.h>
#include <mpm/io/particle_output.h>
#include <mpm/io/png_preview.h>
#include <mpm/io/summary_json.h>
#include <mpm/io/surface_output.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

namespace mpm {

namespace runner_detail {

//! A state without data besides its particles and stages (CoupledState): checkpoints store
//! nothing more. MpmState's own overloads (state.h), more specialised, take precedence.
template <class State>
CarriedData carried_state(const State& /*state*/) {
  return {};
}
template <class State>
void restore_state(State& /*state*/, const CarriedData& /*data*/) {}
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

//! Above this many bytes of expected output, a run warns at its start.
inline constexpr double kOutputWarningBytes = 20e9;

//! The checkpoint a stopped run writes when the stop came between two frames.
inline constexpr const char* kStoppedCheckpoint = "checkpoint_stopped.h5";

//! A new run id: 48 random bits as a decimal integer, so that diagnostics.csv holds it exactly.
inline std::string new_run_id() {
  std::random_device device;
  const auto now = static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
  const std::uint64_t bits = (std::uint64_t(device()) << 32) ^ device() ^ (now * 0x9e3779b97f4a7c15ull);
  return std::to_string(bits & ((std::uint64_t(1) << 48) - 1));
}

//! The frame number NNNN of a per-frame output "<stem>_NNNN.<h5|xdmf|png>", or -1.
inline int output_frame(const std::string& name) {
  const std::size_t dot = name.rfind('.'), bar = name.rfind('_', dot);
  if (dot == std::string::npos || bar == std::string::npos || dot - bar < 5) return -1;
  const std::string ext = name.substr(dot + 1), digits = name.substr(bar + 1, dot - bar - 1);
  if ((ext != "h5" && ext != "xdmf" && ext != "png") || digits.size() > 9 ||
      digits.find_first_not_of("0123456789") != std::string::npos)
    return -1;
  return std::stoi(digits);
}

//! The files a run writes in its folder: per-frame outputs, time series, the stopped checkpoint,
//! diagnostics and summary. Anything else in the folder is not the runner's.
inline bool is_run_output(const std::string& name) {
  return output_frame(name) >= 0 || name == "diagnostics.csv" || name == "summary.json" || name == kStoppedCheckpoint ||
         (name.size() > 5 && name.ends_with(".xdmf"));
}

//! Removes the files of `folder` for which `doomed(name)` holds; returns how many.
template <class Predicate>
std::size_t remove_files(const std::filesystem::path& folder, Predicate doomed) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    if (entry.is_regular_file() && doomed(entry.path().filename().string())) files.push_back(entry.path());
  for (const auto& file : files) std::filesystem::remove(file);
  return files.size();
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
  c.push_back("run_id");
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
  // Over the resolved keys that determine the solution: time.end and output.* may change between
  // a run and its restart. The content of input files has its own digests (verify_restart).
  io::Checksum digest;
  for (const auto& [key, value] : scene_.resolved())
    if (key != "time.end" && key.rfind("output.", 0) != 0) digest.add(key + "=" + value + ";");
  return digest.hex();
}

template <int dim, class State>
int Runner<dim, State>::open_output(State& state, Pipeline<State>& pipeline) {
  // Half-written files of a run that was killed in this folder (io/atomic_file.h).
  io::remove_stale_temporaries(out_);
  if (!cl_.restart) {
    std::filesystem::create_directories(out_);
    // A folder with diagnostics.csv holds an earlier run: its files go, so that none of its
    // frames or checkpoints are mistaken for this run's.
    if (std::filesystem::exists(out_ / "diagnostics.csv")) {
      const std::size_t removed = runner_detail::remove_files(out_, runner_detail::is_run_output);
      if (!cl_.quiet)
        std::cerr << app_ << ": removed " << removed << " files of the earlier run in '" << out_.string() << "'\n";
    }
    run_id_ = runner_detail::new_run_id();
    csv_.open(out_ / "diagnostics.csv", columns(state, pipeline));
    steps_at_last_frame_ = state.step;
    return 0;
  }
  verify<InputError>(std::filesystem::exists(out_ / "diagnostics.csv"),
                     "--restart continues a run in its output folder, but '" + out_.string() +
                         "' holds no diagnostics.csv: pass --out with the folder of the run that wrote '" +
                         *cl_.restart + "'");
  // Everything is read and verified before any file of the folder changes, so a refused or
  // failed restart leaves the run's files as they were.
  io::CheckpointHeader header;
  for (const PhaseRef<dim>& phase : phases(state))
    io::load_checkpoint<dim>(*cl_.restart, header, *phase.particles, phase.name);
  verify_restart(header);
  csv_.load(out_ / "diagnostics.csv", columns(state, pipeline));
  const std::vector<double> frames = csv_.column("frame"), runs = csv_.column("run_id");
  const double run = static_cast<double>(std::stoull(header.run_id));
  std::set<int> kept;
  for (std::size_t r = 0; r < frames.size(); ++r) {
    if (frames[r] > header.frame) continue;
    verify<InputError>(runs[r] == run, "'" + (out_ / "diagnostics.csv").string() + "' holds frame " +
                                           runner_detail::number(frames[r]) + " of run " +
                                           std::to_string(static_cast<long long>(runs[r])) + ", but checkpoint '" +
                                           *cl_.restart + "' belongs to run " + header.run_id +
                                           ": --out must be the folder of the run that wrote the checkpoint");
    kept.insert(static_cast<int>(frames[r]));
  }
  verify<InputError>(static_cast<int>(kept.size()) == header.frame + 1 && *kept.begin() == 0,
                     "'" + (out_ / "diagnostics.csv").string() + "' holds " + std::to_string(kept.size()) +
                         " of the frames 0-" + std::to_string(header.frame) + " that checkpoint '" + *cl_.restart +
                         "' continues: restart from an earlier checkpoint of this folder");

  // The state's own data (domain corners) first: a checkpoint without them is refused before
  // anything in the folder changes.
  using runner_detail::restore_state;
  restore_state(state, header.stage_data);

  // Verified: the folder continues from the checkpoint. Later frames are written again.
  const std::filesystem::path from = std::filesystem::weakly_canonical(*cl_.restart);
  runner_detail::remove_files(out_, [&](const std::string& name) {
    if (name == runner_detail::kStoppedCheckpoint) return std::filesystem::weakly_canonical(out_ / name) != from;
    return name == "summary.json" || runner_detail::output_frame(name) > header.frame;
  });
  csv_.keep_until(header.frame);
  run_id_ = header.run_id;
  state.time = header.time;
  state.step = header.step;
  state.dt = header.dt_previous;
  steps_at_last_frame_ = header.frame_step;
  pipeline.restore(header.stage_data);
  const std::string first_series = runner_detail::series_stem(phases(state).front().name);
  for (int f = 0; f <= header.frame; ++f)
    if (std::filesystem::exists(out_ / io::particle_file_name(f, first_series)))
      frames_written_.emplace_back(f, f * settings_.frame_dt);
  return header.frame;
}

template <int dim, class State>
void Runner<dim, State>::verify_restart(const io::CheckpointHeader& header) const {
  const std::string checkpoint = "checkpoint '" + *cl_.restart + "'";
  verify<InputError>(header.dim == dim,
                     checkpoint + " is " + std::to_string(header.dim) + "D, the scene is " + std::to_string(dim) + "D");
  verify<InputError>(header.scene_digest == scene_digest(),
                     checkpoint + " was written by another scene (digest " + header.scene_digest + ", this scene " +
                         scene_digest() + "): a restart needs the same keys and values, except time.end and output.*");
  for (const io::InputFile& now : inputs_) {
    const auto then = std::find_if(header.inputs.begin(), header.inputs.end(),
                                   [&](const io::InputFile& f) { return f.key == now.key; });
    verify<InputError>(then != header.inputs.end(), checkpoint + " does not record the input file of " + now.key +
                                                        " ('" + now.path + "'): it was written by another scene");
    verify<InputError>(then->digest == now.digest, "the input file '" + now.path + "' (" + now.key +
                                                       ") changed since " + checkpoint +
                                                       " was written (content digest " + then->digest + ", now " +
                                                       now.digest + "): restore the file, or start a new run");
  }
  verify<InputError>(header.inputs.size() == inputs_.size(),
                     checkpoint + " depends on " + std::to_string(header.inputs.size()) +
                         " input files, the scene on " + std::to_string(inputs_.size()) +
                         ": it was written by another scene");
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
  r.push_back(static_cast<double>(std::stoull(run_id_)));
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
  start_ = last_checkpoint_ = std::chrono::steady_clock::now();
  inputs_.clear();
  for (const auto& [key, path] : scene_.input_files()) inputs_.push_back({key, path.string(), io::file_digest(path)});
  const StopSignals signals;  // from here on, SIGINT and SIGTERM stop the run with a checkpoint
  const int first_frame = open_output(state, pipeline);
  stage_seconds_at_last_frame_.assign(pipeline.stage_names().size(), 0.0);
  if (!cl_.restart) {
    append_diagnostics(state, 0, pipeline);
    write_frame(state, 0);
    warn_output_size(0);
  }

  const int frames = settings_.frame_count();
  const auto& out = settings_.output;
  for (int frame = first_frame + 1; frame <= frames; ++frame) {
    const bool reached =
        advance(state, pipeline, std::min(frame * settings_.frame_dt, settings_.end_time),
                settings_.max_steps_per_frame, 1e-12 * settings_.frame_dt, [] { return StopSignals::received() != 0; });
    pipeline.synchronize(state);
    if (!reached) stop(state, pipeline, frame - 1, true);
    append_diagnostics(state, frame, pipeline);
    write_frame(state, frame);
    if (frame == first_frame + 1 && cl_.restart) warn_output_size(frame);
    const double minutes =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint_).count() / 60.0;
    const bool stopping = StopSignals::received() != 0 && frame < frames;
    if (frame == frames || stopping || (out.checkpoint_every > 0 && frame % out.checkpoint_every == 0) ||
        (out.checkpoint_minutes > 0 && minutes >= out.checkpoint_minutes))
      write_checkpoint(state, pipeline, frame, out_ / runner_detail::numbered("checkpoint", frame, ".h5"));
    if (stopping) stop(state, pipeline, frame, false);
    if (!cl_.quiet) progress(state, frame, frame == frames);
  }
  // A restart from the last frame's checkpoint runs no frame: the checkpoint is written again
  // (the same state), so that summary.json names the state's checksum as after any run.
  if (state_checksum_.empty())
    write_checkpoint(state, pipeline, first_frame, out_ / runner_detail::numbered("checkpoint", first_frame, ".h5"));

  // Under --check, every solve of the run must have converged: a stage that may go on past a
  // failed solve (on_failure: warn) counts them in a column "<solve>_unconverged", and a solve
  // that flags its round-off floor must have met check_max_solve_residual (core/app.h).
  if (cl_.check)
    for (const std::string& column : csv_.columns()) {
      if (column.ends_with("_unconverged")) check_value(column, csv_.column(column).back(), 0.0, 0.0);
      if (column.ends_with("_round_off")) {
        const std::string solve = column.substr(0, column.size() - std::string("_round_off").size());
        check_solve_residuals(solve, history_or_zero(solve + "_residual"), csv_.column(column),
                              check_max_solve_residual);
      }
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
    memory_.emplace_back(prefix + "grid.index", phase.index_bytes);
  }
  std::cerr << "\n" << app_ << ": stages run, in order, with their total time\n" << stage_table_;
  std::cerr << "memory held per field (bytes)\n";
  for (const auto& [name, bytes] : memory_)
    if (bytes > 0) std::fprintf(stderr, "  %-31s %14zu\n", name.c_str(), bytes);
}

template <int dim, class State>
void Runner<dim, State>::write_checkpoint(State& state, const Pipeline<State>& pipeline, int frame,
                                          const std::filesystem::path& path) {
  std::vector<io::CheckpointPhase<dim>> stored;
  for (const PhaseRef<dim>& phase : phases(state)) stored.push_back({phase.name, phase.particles});
  CarriedData carried = pipeline.carried();
  using runner_detail::carried_state;
  for (auto& entry : carried_state(std::as_const(state))) carried.push_back(std::move(entry));
  io::CheckpointHeader h{dim,        frame,
                         state.step, state.time,
                         state.dt,   scene_digest(),
                         run_id_,    steps_at_last_frame_,
                         inputs_,    std::move(carried)};
  state_checksum_ = io::save_checkpoint<dim>(path, stored, h);
  last_checkpoint_ = std::chrono::steady_clock::now();
  if (path.filename() != runner_detail::kStoppedCheckpoint) prune_checkpoints();
}

template <int dim, class State>
void Runner<dim, State>::prune_checkpoints() const {
  // The newest checkpoints_kept numbered checkpoints stay; a stopped run's checkpoint is older
  // than the one just written.
  std::vector<int> numbered;
  for (const auto& entry : std::filesystem::directory_iterator(out_)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("checkpoint_", 0) == 0 && runner_detail::output_frame(name) >= 0)
      numbered.push_back(runner_detail::output_frame(name));
  }
  std::sort(numbered.begin(), numbered.end());
  const std::size_t kept = static_cast<std::size_t>(settings_.output.checkpoints_kept);
  for (std::size_t i = 0; i + kept < numbered.size(); ++i)
    std::filesystem::remove(out_ / runner_detail::numbered("checkpoint", numbered[i], ".h5"));
  std::filesystem::remove(out_ / runner_detail::kStoppedCheckpoint);
}

template <int dim, class State>
void Runner<dim, State>::warn_output_size(int frame) const {
  // The files of one frame times the frames still to come: a run that would fill a disk says so
  // at its start.
  std::uintmax_t bytes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(out_))
    if (runner_detail::output_frame(entry.path().filename().string()) == frame &&
        entry.path().filename().string().rfind("checkpoint_", 0) != 0)
      bytes += entry.file_size();
  const double total = double(bytes) * (settings_.frame_count() - frame + 1);
  if (total > runner_detail::kOutputWarningBytes)
    std::fprintf(stderr,
                 "%s: warning: the output of this run will take about %.3g GB (%.3g MB a frame, %d frames) in '%s'; "
                 "raise time.frame_dt or turn off output.particles / output.png to write less\n",
                 app_.c_str(), total / 1e9, bytes / 1e6, settings_.frame_count() - frame + 1, out_.c_str());
}

template <int dim, class State>
void Runner<dim, State>::stop(State& state, const Pipeline<State>& pipeline, int frame, bool mid_frame) {
  const std::filesystem::path path =
      out_ / (mid_frame ? runner_detail::kStoppedCheckpoint : runner_detail::numbered("checkpoint", frame, ".h5"));
  if (mid_frame) write_checkpoint(state, pipeline, frame, path);
  const int signal = StopSignals::received();
  char where[160];
  std::snprintf(where, sizeof where, "at t = %.6g s (step %lld, after frame %d)", state.time,
                static_cast<long long>(state.step), frame);
  throw StopRequested(signal, std::string("stopped by ") + (signal == SIGINT ? "SIGINT" : "SIGTERM") + " " + where +
                                  "; checkpoint '" + path.string() + "' written: continue with --restart '" +
                                  path.string() + "'");
}

template <int dim, class State>
void Runner<dim, State>::write_frame(State& state, int frame) {
  const auto all = phases(state);
  if (settings_.output.particles) {
    frames_written_.emplace_back(frame, state.time);
    for (const PhaseRef<dim>& phase : all) {
      const std::string stem = runner_detail::series_stem(phase.name);
      io::write_particles(out_ / io::particle_file_name(frame, stem), *phase.particles, state.time, frame, run_id_);
      io::write_time_series_xdmf(out_, frames_written_, stem);
    }
    if constexpr (requires { state.adaptive; })  // the leaves of an adaptive grid (io/cell_output.h)
      if (state.adaptive) {
        io::write_cells(out_ / io::particle_file_name(frame, "cells"), state.adaptive->tree(), state.time, frame,
                        run_id_);
        io::write_cells_time_series<dim>(out_, frames_written_);
      }
    if constexpr (requires { state.domains; })  // the bodies' surface (io/surface_output.h)
      if (state.domains && !state.domains->surface.empty()) {
        io::write_surface(out_ / io::particle_file_name(frame, "surface"), *state.domains, state.time, frame, run_id_);
        io::write_surface_time_series<dim>(out_, frames_written_);
        if (!state.domains->embedded_triangles.empty()) {  // a mesh the bodies were seeded from
          io::write_embedded_mesh(out_ / io::particle_file_name(frame, "mesh"), *state.domains, state.time, frame,
                                  run_id_);
          io::write_embedded_mesh_time_series(out_, frames_written_);
        }
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
                                                           {"run_id", run_id_},
                                                           {"state_checksum", "0x" + state_checksum_},
                                                           {"wall_seconds", std::to_string(wall_seconds_)}};
  std::string stages;
  for (const auto& s : stage_names_) stages += (stages.empty() ? "" : ",") + s;
  info.emplace_back("stages", stages);
  info.emplace_back("steps", std::to_string(steps_at_last_frame_));
  info.emplace_back("threads", std::to_string(worker_threads()));
  info.emplace_back("particles", std::to_string(particle_count_));
  info.emplace_back("grid_nodes", std::to_string(grid_nodes_));
  for (const auto& [name, bytes] : memory_) info.emplace_back("memory_bytes." + name, std::to_string(bytes));
  io::write_summary(out_ / "summary.json", results, scene_.resolved(), info);
}

}  // namespace mpm
