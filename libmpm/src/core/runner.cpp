#include <mpm/core/error.h>
#include <mpm/core/runner.h>
#include <mpm/io/checkpoint.h>
#include <mpm/io/diagnostics_csv.h>
#include <mpm/io/particle_output.h>
#include <mpm/io/png_preview.h>
#include <mpm/io/summary_json.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace mpm {

namespace {
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

std::string numbered(const std::string& stem, int frame, const std::string& ext) {
  char name[64];
  std::snprintf(name, sizeof name, "%s_%04d%s", stem.c_str(), frame, ext.c_str());
  return name;
}
}  // namespace

template <int dim>
Runner<dim>::Runner(std::string app_name, CommandLine command_line, const Config& scene,
                    const SceneSettings<dim>& settings)
    : app_(std::move(app_name)), cl_(std::move(command_line)), scene_(scene), settings_(settings),
      out_(cl_.out_dir) {}

template <int dim>
std::vector<std::string> Runner<dim>::columns(const Pipeline<State>& pipeline) const {
  std::vector<std::string> c = {"frame", "time", "dt", "steps", "kinetic_energy", "elastic_energy",
                                "gravity_potential", "mass", "momentum_x", "momentum_y"};
  if (dim == 3) c.push_back("momentum_z");
  c.push_back("max_speed");
  for (const auto& [name, fn] : extra_) c.push_back(name);
  for (const auto& stage : pipeline.stage_names()) c.push_back("seconds_" + stage);
  return c;
}

template <int dim>
std::string Runner<dim>::scene_digest() const {
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

template <int dim>
int Runner<dim>::open_output(State& state, const Pipeline<State>& pipeline) {
  if (!cl_.restart) {
    std::filesystem::create_directories(out_);
    csv_.open(out_ / "diagnostics.csv", columns(pipeline));
    return 0;
  }
  verify<InputError>(std::filesystem::exists(out_ / "diagnostics.csv"),
                     "--restart continues a run in its output folder, but '" + out_.string() +
                         "' holds no diagnostics.csv: pass --out with the folder of the run that wrote '" +
                         *cl_.restart + "'");
  io::CheckpointHeader header;
  state.particles = io::load_checkpoint<dim>(*cl_.restart, header);
  verify<InputError>(header.dim == dim, "checkpoint '" + *cl_.restart + "' is " + std::to_string(header.dim) +
                                            "D, the scene is " + std::to_string(dim) + "D");
  verify<InputError>(header.scene_digest == scene_digest(),
                     "checkpoint '" + *cl_.restart + "' was written by another scene (digest " +
                         header.scene_digest + ", this scene " + scene_digest() +
                         "): a restart needs the same keys and values, except time.end and output.*");
  state.time = header.time;
  state.step = header.step;
  csv_.open_for_restart(out_ / "diagnostics.csv", columns(pipeline), header.frame);
  for (int f = 0; f <= header.frame; ++f)
    if (std::filesystem::exists(out_ / io::particle_file_name(f)))
      frames_written_.emplace_back(f, f * settings_.frame_dt);
  return header.frame;
}

template <int dim>
void Runner<dim>::append_diagnostics(const State& state, int frame, const Pipeline<State>& pipeline) {
  const Particles<dim>& P = state.particles;
  double kinetic = 0, potential = 0, mass = 0, max_speed2 = 0;
  Vec<dim> momentum = Vec<dim>::Zero();
  for (std::size_t p = 0; p < P.size(); ++p) {
    kinetic += 0.5 * P.mass[p] * P.v[p].squaredNorm();
    potential -= P.mass[p] * state.gravity.dot(P.x[p]);
    mass += P.mass[p];
    momentum += P.mass[p] * P.v[p];
    max_speed2 = std::max(max_speed2, P.v[p].squaredNorm());
  }
  std::vector<double> r = {double(frame), state.time, state.dt, double(state.step - steps_at_last_frame_),
                           kinetic, elastic_energy_ ? elastic_energy_(state) : 0.0, potential, mass};
  for (int a = 0; a < dim; ++a) r.push_back(momentum[a]);
  r.push_back(std::sqrt(max_speed2));
  for (const auto& [name, fn] : extra_) r.push_back(fn(state));
  const StageTimes& t = pipeline.times();
  for (std::size_t s = 0; s < t.seconds.size(); ++s) {
    r.push_back(t.seconds[s] - stage_seconds_at_last_frame_[s]);
    stage_seconds_at_last_frame_[s] = t.seconds[s];
  }
  steps_at_last_frame_ = state.step;
  csv_.append(r);
}

template <int dim>
void Runner<dim>::advance(State& state, Pipeline<State>& pipeline, double t_end, int frame) {
  int steps = 0;
  while (state.time < t_end - 1e-12 * settings_.frame_dt) {
    state.dt_limit = t_end - state.time;
    pipeline.step(state);
    if (!(state.dt > 0.0) || ++steps > settings_.max_steps_per_frame)
      throw NumericalError("stage 'time_step': the time step collapsed to " + number(state.dt) + " s at t = " +
                           number(state.time) + " s (more than " + std::to_string(settings_.max_steps_per_frame) +
                           " steps in frame " + std::to_string(frame) + ")");
    state.time = state.dt >= state.dt_limit ? t_end : state.time + state.dt;
    ++state.step;
  }
}

template <int dim>
void Runner<dim>::run(State& state, Pipeline<State>& pipeline) {
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
    advance(state, pipeline, std::min(frame * settings_.frame_dt, settings_.end_time), frame);
    append_diagnostics(state, frame, pipeline);
    write_frame(state, frame);
    const bool checkpoint = frame == frames ||
                            (settings_.output.checkpoint_every > 0 && frame % settings_.output.checkpoint_every == 0);
    if (checkpoint) {
      io::CheckpointHeader h{dim, frame, state.step, state.time, state.dt, scene_digest()};
      io::save_checkpoint(out_ / numbered("checkpoint", frame, ".h5"), state.particles, h);
    }
    if (!cl_.quiet) progress(state, frame, frame == frames);
  }

  wall_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  stage_names_ = pipeline.stage_names();
  stage_table_ = pipeline.times().table();
  particle_count_ = state.particles.size();
  grid_nodes_ = state.grid.node_storage();
  memory_ = state.particles.memory_per_field();
  for (const auto& m : state.grid.memory_per_field()) memory_.push_back(m);
  std::cerr << "\n" << app_ << ": stages run, in order, with their total time\n" << stage_table_;
  std::cerr << "memory held per field (bytes)\n";
  for (const auto& [name, bytes] : memory_)
    if (bytes > 0) std::fprintf(stderr, "  %-22s %14zu\n", name.c_str(), bytes);
}

template <int dim>
void Runner<dim>::write_frame(const State& state, int frame) {
  if (settings_.output.particles) {
    io::write_particles(out_ / io::particle_file_name(frame), state.particles, state.time, frame);
    frames_written_.emplace_back(frame, state.time);
    io::write_time_series_xdmf(out_, frames_written_);
  }
  if (settings_.output.png) {
    io::PreviewOptions o;
    for (int a = 0; a < dim; ++a) {
      o.domain_lo[a] = settings_.domain_lo[a];
      o.domain_hi[a] = settings_.domain_hi[a];
    }
    o.width_px = settings_.output.png_width;
    o.color_by = settings_.output.color_by;
    if (!state.particles.volume0.empty()) {  // splats about as wide as the particle spacing
      const double spacing = std::pow(state.particles.volume0[0], 1.0 / dim);
      o.point_radius_px = std::max(1.0, 0.6 * spacing * o.width_px / (o.domain_hi[0] - o.domain_lo[0]));
    }
    io::write_png_preview(out_ / numbered("preview", frame, ".png"), state.particles, o);
  }
}

template <int dim>
void Runner<dim>::progress(const State& state, int frame, bool last) const {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const int frames = settings_.frame_count();
  const double eta = elapsed / frame * (frames - frame);
  std::fprintf(stderr, "\r[%s] frame %d/%d  t = %.4g s  steps %lld  elapsed %.1f s  ETA %.1f s   %s",
               app_.c_str(), frame, frames, state.time, static_cast<long long>(state.step), elapsed,
               eta, last ? "\n" : "");
  std::fflush(stderr);
}

template <int dim>
void Runner<dim>::write_summary(const std::vector<std::pair<std::string, double>>& results) const {
  std::vector<std::pair<std::string, std::string>> info = {
      {"app", app_}, {"scene_file", cl_.scene_file}, {"dim", std::to_string(dim)},
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

template class Runner<2>;
template class Runner<3>;

}  // namespace mpm
