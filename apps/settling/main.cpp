// settling: a uniform suspension of one grain size (volume fraction phi) in the lower part of
// a closed column of fluid settles under gravity (coupling/settling_column.h for the keys).
//
//   settling data/scenes/settling.yaml
//   settling data/scenes/settling.yaml --set sediment.volume_fraction=0.2 --set drag.law=schiller_naumann
//
// diagnostics.csv, one row per frame: time [s], settling_velocity (mean downward velocity of
// the grains above the deposit) [m/s], suspension_top (upper edge of the suspension) [m].
// summary.json (speeds positive downwards, over the steady window: frames with
// t >= measure.start and the upper edge still above measure.min_top):
//   settling_velocity, interface_velocity (least-squares slope of the upper edge),
//   terminal_velocity_stokes = (rho_s - rho_w) g d^2 / (18 mu), hindered_velocity (the speed
//   the drag law implies, settling_column.h), reynolds_number = rho_w v d / mu.
// --check: settling_velocity within 10 % of hindered_velocity. For the Stokes and the
// Schiller-Naumann laws at low Re this is n_w^2 v_St (n_w = 1 - phi; docs/coupling.md).
#include <coupling/settling_column.h>
#include <mpm/core/app.h>
#include <mpm/core/command_line.h>
#include <mpm/core/error.h>
#include <mpm/io/diagnostics_csv.h>
#include <mpm/io/summary_json.h>

#include <cstdio>
#include <filesystem>
#include <iostream>

using namespace mpm;

namespace {

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  verify<InputError>(!cl.restart, "settling: --restart is not supported by this app");
  coupling::SettlingScene<dim> col = coupling::load_settling_column<dim>(scene);
  const std::optional<Config> measure = scene.optional_child("measure");
  const SceneSettings<dim>& settings = col.scene.settings;
  const double start = measure ? measure->number("start", 0.25 * settings.end_time, Range::non_negative())
                               : 0.25 * settings.end_time;
  const double dx = settings.dx;
  const double min_top = measure ? measure->number("min_top", 4.0 * dx, Range::non_negative()) : 4.0 * dx;
  scene.reject_unknown_keys();

  auto pipeline = coupling::make_coupled_pipeline(col.scene);
  coupling::CoupledState<dim>& s = col.scene.state;
  const std::filesystem::path out(cl.out_dir);
  std::filesystem::create_directories(out);
  io::DiagnosticsCsv csv;
  csv.open(out / "diagnostics.csv", {"frame", "time", "settling_velocity", "suspension_top", "steps"});

  // Sums of the steady window: mean speed and the least-squares slope of the edge.
  double sum_v = 0.0, st = 0.0, sh = 0.0, stt = 0.0, sth = 0.0;
  int n = 0;
  const int frames = settings.frame_count();
  for (int f = 0; f <= frames; ++f) {
    if (f > 0) coupling::advance(s, pipeline, std::min(f * settings.frame_dt, settings.end_time));
    const double v = -coupling::mean_sediment_velocity(s, 2.0 * dx);
    const double top = coupling::suspension_top(s, col.column, 2.0 * dx);
    csv.append({double(f), s.time, v, top, double(s.step)});
    if (!cl.quiet) std::fprintf(stderr, "\rsettling: frame %d/%d t = %.4g s", f, frames, s.time);
    if (s.time >= start && top > min_top) {
      sum_v += v;
      st += s.time;
      sh += top;
      stt += s.time * s.time;
      sth += s.time * top;
      ++n;
    }
  }
  if (!cl.quiet) std::fprintf(stderr, "\n");
  verify<InputError>(n >= 2, "settling: fewer than two frames in the steady window (measure.start = " +
                                 std::to_string(start) + " s); run longer or start earlier");
  const double settling = sum_v / n;
  const double interface = -(n * sth - st * sh) / (n * stt - st * st);
  const double hindered = col.column.hindered_velocity();
  io::write_summary(out / "summary.json",
                    {{"settling_velocity", settling},
                     {"interface_velocity", interface},
                     {"terminal_velocity_stokes", col.column.stokes_velocity()},
                     {"hindered_velocity", hindered},
                     {"reynolds_number", col.column.reynolds(settling)},
                     {"window_frames", double(n)}},
                    scene.resolved(), {{"app", "settling"}});
  if (cl.check) return check_value("settling_velocity", settling, hindered, 0.1 * hindered) ? 0 : 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "settling",
                       "Settling of a uniform suspension in a closed column (coupled step)", run<2>, run<3>);
}
