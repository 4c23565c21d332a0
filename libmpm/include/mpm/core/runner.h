#pragma once
//! Runs a pipeline frame by frame and writes everything a run leaves in its output folder:
//! particles_NNNN.h5 + .xdmf (and particles.xdmf, the time series), preview_NNNN.png,
//! diagnostics.csv (one row per frame, a seconds column per stage), checkpoint_NNNN.h5,
//! summary.json; a progress line with ETA on stderr and, at the end, the per-stage time
//! table and the memory held per field. Besides the columns every run has and those an app adds,
//! diagnostics.csv holds what each stage reports (Stage::diagnostics(): solver iterations and
//! residuals, masses emitted and removed).
//!
//! A state of several particle phases (libcoupling's CoupledState, through its `phases`
//! function, state.h) writes one particle series per phase named after it (fluid_NNNN.h5 +
//! fluid.xdmf, sediment_NNNN.h5 + sediment.xdmf), draws them all in one preview, sums the
//! diagnostics over the phases and adds a mass_<phase> column per phase, and stores every
//! phase in one checkpoint. The definitions are in runner_impl.h; libmpm instantiates
//! Runner<dim> for MpmState, libcoupling for its state.
//!
//! Integrity (docs/reliability.md): every run has a run id, stored in each HDF5 file, in the
//! run_id column of diagnostics.csv and in summary.json. A fresh run into a folder that holds an
//! earlier run's output first removes that run's files (frames, checkpoints, diagnostics,
//! summary; nothing else). A restart verifies the checkpoint (checksums, scene digest, input file
//! digests) and that diagnostics.csv belongs to the same run and holds every frame up to the
//! checkpoint's, before it changes anything; then it removes the outputs of later frames, which
//! the continued run writes again. Checkpoints are written every output.checkpoint_every frames,
//! at the first frame end after output.checkpoint_minutes of wall-clock time, and after the last
//! frame; the newest output.checkpoints_kept are kept. SIGINT and SIGTERM stop the run after the
//! current step with a checkpoint (core/stop_signals.h).
#include <mpm/core/command_line.h>
#include <mpm/core/config.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/state.h>
#include <mpm/io/checkpoint.h>
#include <mpm/io/diagnostics_csv.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace mpm {

template <int dim, class State = MpmState<dim>>
class Runner {
public:
  using Column = std::function<double(const State&)>;

  Runner(std::string app_name, CommandLine command_line, const Config& scene, const SceneSettings<dim>& settings);

  //! Elastic energy of the state [J] (the solid supplies it; 0 without).
  void set_elastic_energy(Column energy) { elastic_energy_ = std::move(energy); }
  //! An extra diagnostics column, evaluated once per frame.
  void add_column(std::string name, Column value) { extra_.emplace_back(std::move(name), std::move(value)); }
  //! Every value of a diagnostics column so far, frame 0 first (rows before a restart included).
  std::vector<double> history(const std::string& column) const { return csv_.column(column); }
  //! history(column), or zeros when no stage reports that column (inflow_mass_sediment of a
  //! scene without sediment emitters).
  std::vector<double> history_or_zero(const std::string& column) const;

  //! Creates the output folder (or continues from --restart) and runs all frames.
  void run(State& state, Pipeline<State>& pipeline);

  //! Writes summary.json: results, the resolved scene parameters and run information.
  void write_summary(const std::vector<std::pair<std::string, double>>& results) const;

  const std::filesystem::path& out_dir() const { return out_; }

  //! The id of this run: a new one for a fresh run, the checkpoint's for a restart.
  const std::string& run_id() const { return run_id_; }

private:
  std::vector<std::string> columns(State& state, const Pipeline<State>& pipeline) const;
  std::string scene_digest() const;
  int open_output(State& state, Pipeline<State>& pipeline);  // returns the first frame to run
  void verify_restart(const io::CheckpointHeader& header) const;
  void append_diagnostics(State& state, int frame, const Pipeline<State>& pipeline);
  void write_frame(State& state, int frame);
  void write_checkpoint(State& state, const Pipeline<State>& pipeline, int frame, const std::filesystem::path& path);
  void prune_checkpoints() const;
  void warn_output_size(int frame) const;
  [[noreturn]] void stop(State& state, const Pipeline<State>& pipeline, int frame, bool mid_frame);
  void progress(const State& state, int frame, bool last) const;

  std::string app_;
  CommandLine cl_;
  const Config& scene_;
  SceneSettings<dim> settings_;
  std::filesystem::path out_;
  Column elastic_energy_;
  std::vector<std::pair<std::string, Column>> extra_;
  io::DiagnosticsCsv csv_;
  std::string run_id_;
  std::string state_checksum_;  //!< of the particles in the last checkpoint written
  std::vector<io::InputFile> inputs_;
  std::chrono::steady_clock::time_point last_checkpoint_;
  std::vector<std::pair<int, double>> frames_written_;
  std::vector<double> stage_seconds_at_last_frame_;
  Index steps_at_last_frame_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::string stage_table_;
  std::vector<std::pair<std::string, std::size_t>> memory_;
  std::vector<std::string> stage_names_;
  double wall_seconds_ = 0.0;
  std::size_t particle_count_ = 0, grid_nodes_ = 0;
};

}  // namespace mpm
