// study: error against run time. Runs one app over a sweep of a parameter for several methods
// and writes, into --out, study.csv (one row per case), study.md (the table, the observed
// convergence orders and the reference), and study.png (log-log error against wall time, one
// curve per method; drawn by gnuplot).
//
//   study data/studies/vibrating_bar_kernels.yaml --out out/study_bar
//   study data/studies/vibrating_bar_kernels.yaml --check     # assert each method's min_order
//
// The sweep file (paths relative to it):
//   title: ...                    reference: ../reference/x.md   (where the exact answer comes from)
//   app: vibrating_bar            scene: ../scenes/vibrating_bar.yaml
//   error: error                  (the summary.json result that measures the error)
//   set: [time.end=0.4]           (overrides for every case)
//   parameter: {key: bar.cells, values: [16, 32, 64], spacing: inverse}   (h ~ 1/value)
//   methods: [{name: cubic, set: [grid.kernel=cubic], min_order: 0.9}, ...]
//   (a method's per_value: [{key: adaptive.surface_band, values: [...]}]: keys whose value
//    follows the parameter, one per parameter value, e.g. lengths held at a number of cells)
//   notes: |                      (optional Markdown printed under the tables: what the numbers
//     ...                          mean, what limits them)
#include <mpm/core/app.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/number_text.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

using namespace mpm;
namespace fs = std::filesystem;

namespace {

struct Method {
  std::string name;
  std::vector<std::string> overrides;
  double min_order;  // NaN: no assertion
  //! Keys set to their i-th value in the case of the parameter's i-th value.
  std::vector<std::pair<std::string, std::vector<double>>> per_value;
};

struct Case {
  std::string method;
  double value = 0, seconds = 0, error = 0, steps = 0, particles = 0, nodes = 0;
};

std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

//! Least-squares slope of log(y) against log(x).
double log_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    n += 1, sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

//! A case whose solves did not all converge (a "<solve>_unconverged" column of its diagnostics
//! not 0 at the end, pressure.on_failure: warn) has an error that measures the solver cap, not
//! the method: the study refuses it rather than report it. So does a case whose pressure solves
//! "converged" to a tolerance loosened in the sweep: a frame's pressure_residual above
//! check_max_solve_residual (core/app.h, 1e-6) that pressure_round_off does not flag.
void refuse_unconverged(const fs::path& out) {
  std::ifstream in(out / "diagnostics.csv");
  std::string header, line, last;
  std::getline(in, header);
  std::vector<std::string> columns;
  {
    std::stringstream names(header);
    for (std::string name; std::getline(names, name, ',');) columns.push_back(name);
  }
  const auto index = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin());
  };
  const std::size_t residual = index("pressure_residual"), round_off = index("pressure_round_off");
  std::string loose;  // the first frame whose pressure solve stopped above the bound
  for (int frame = 0; std::getline(in, line); ++frame) {
    if (line.empty()) continue;
    last = line;
    std::vector<std::string> cells;
    std::stringstream values(line);
    for (std::string value; std::getline(values, value, ',');) cells.push_back(value);
    const bool at_round_off = round_off < cells.size() && std::stod(cells[round_off]) != 0.0;
    if (loose.empty() && residual < cells.size() && !at_round_off &&
        !(std::stod(cells[residual]) <= check_max_solve_residual))
      loose = cells[residual] + " in frame " + std::to_string(frame);
  }
  std::stringstream names(header), values(last);
  for (std::string name, value; std::getline(names, name, ',') && std::getline(values, value, ',');)
    if (name.ends_with("_unconverged") && std::stod(value) != 0.0)
      throw NumericalError("study: " + value + " solves of case " + out.string() + " did not converge (" + name +
                           "): its error would measure the solver's cap, not the method");
  if (!loose.empty())
    throw NumericalError(
        "study: the pressure solve of case " + out.string() + " stopped at relative residual " + loose +
        " (above 1e-06: a loosened pressure.tolerance): its error would measure the tolerance, not " + "the method");
}

Case run_case(const fs::path& app, const fs::path& scene, const std::vector<std::string>& overrides,
              const fs::path& out, const std::string& error_key) {
  std::string command = quoted(app.string()) + " " + quoted(scene.string()) + " --quiet --out " + quoted(out.string());
  for (const std::string& o : overrides) command += " --set " + quoted(o);
  command += " > " + quoted((out.string() + ".log")) + " 2>&1";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  Case c;
  c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (status != 0) throw NumericalError("study: case failed (see " + out.string() + ".log): " + command);
  refuse_unconverged(out);
  std::ifstream in(out / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  if (!summary["results"].contains(error_key))
    throw InputError("study: summary.json of " + out.string() + " has no result '" + error_key + "'");
  c.error = summary["results"][error_key].get<double>();
  const auto& info = summary["info"];
  c.steps = std::stod(info["steps"].get<std::string>());
  c.particles = std::stod(info["particles"].get<std::string>());
  c.nodes = std::stod(info["grid_nodes"].get<std::string>());
  return c;
}

void plot(const fs::path& out, const std::string& title, const std::vector<Method>& methods,
          const std::vector<Case>& cases) {
  std::ofstream gp(out / "study.gp");
  gp << "set terminal pngcairo size 800,560\nset output '" << (out / "study.png").string() << "'\n"
     << "set termoption noenhanced\nset title '" << title << "'\nset logscale xy\nset grid\nset key outside right\n"
     << "set xlabel 'wall time [s]'\nset ylabel 'error'\nplot ";
  for (std::size_t m = 0; m < methods.size(); ++m)
    gp << (m ? ", " : "") << "'-' with linespoints lw 2 pt 7 title '" << methods[m].name << "'";
  gp << "\n";
  for (const Method& method : methods) {
    for (const Case& c : cases)
      if (c.method == method.name) gp << c.seconds << " " << c.error << "\n";
    gp << "e\n";
  }
  gp.close();
  if (std::system(("gnuplot " + quoted((out / "study.gp").string())).c_str()) != 0)
    throw IoError("study: gnuplot failed or is missing (install gnuplot-nox); the data is in study.csv");
}

int run(const CommandLine& cl) {
  const Config sweep = Config::load(cl.scene_file, cl.overrides);
  const fs::path here = fs::path(cl.scene_file).parent_path();
  const std::string title = sweep.text("title");
  const std::string app = sweep.text("app");
  const fs::path scene = here / sweep.text("scene");
  const fs::path reference = here / sweep.text("reference");
  const std::string error_key = sweep.text("error");
  const std::vector<std::string> common = sweep.texts("set");
  std::string notes = sweep.text("notes", "");
  notes.erase(notes.find_last_not_of(" \n") + 1);
  const Config parameter = sweep.child("parameter");
  const std::string key = parameter.text("key");
  const std::vector<double> values = parameter.numbers("values", Range::positive());
  const std::string spacing = parameter.choice("spacing", "inverse", {"inverse", "direct", "none"});
  std::vector<Method> methods;
  for (const Config& m : sweep.list("methods")) {
    methods.push_back({m.text("name"), m.texts("set"), m.number("min_order", std::nan(""), Range::any()), {}});
    for (const Config& k : m.list("per_value")) {
      const std::vector<double> follower_values = k.numbers("values");
      if (follower_values.size() != values.size())
        k.fail("values", "needs one value per parameter value (" + std::to_string(values.size()) + "), has " +
                             std::to_string(follower_values.size()));
      methods.back().per_value.emplace_back(k.text("key"), follower_values);
    }
  }
  if (methods.empty()) sweep.fail("methods", "at least one method is required");
  if (!fs::exists(scene)) sweep.fail("scene", "no such file: " + scene.string());
  if (!fs::exists(reference)) sweep.fail("reference", "no such file: " + reference.string());
  const fs::path app_path = fs::canonical("/proc/self/exe").parent_path() / app;
  if (!fs::exists(app_path)) sweep.fail("app", "no app '" + app + "' beside the study program");
  sweep.reject_unknown_keys();

  const fs::path out = cl.out_dir;
  fs::create_directories(out / "cases");
  std::vector<Case> cases;
  for (const Method& method : methods)
    for (std::size_t v = 0; v < values.size(); ++v) {
      const double value = values[v];
      std::vector<std::string> overrides = common;
      overrides.insert(overrides.end(), method.overrides.begin(), method.overrides.end());
      for (const auto& [follower, its_values] : method.per_value)
        overrides.push_back(follower + "=" + exact_number_text(its_values[v]));
      overrides.push_back(key + "=" + exact_number_text(value));
      overrides.push_back("output.png=false");
      overrides.push_back("output.particles=false");
      const fs::path case_dir = out / "cases" / (method.name + "_" + number(value));
      Case c = run_case(app_path, scene, overrides, case_dir, error_key);
      c.method = method.name;
      c.value = value;
      std::fprintf(stderr, "study: %-14s %s = %-8s error %.4e  %.2f s\n", method.name.c_str(), key.c_str(),
                   number(value).c_str(), c.error, c.seconds);
      cases.push_back(c);
    }

  std::ofstream csv(out / "study.csv");
  csv << "method," << key << ",wall_seconds,steps,particles,grid_nodes,error\n";
  for (const Case& c : cases)
    csv << c.method << "," << c.value << "," << c.seconds << "," << c.steps << "," << c.particles << "," << c.nodes
        << "," << c.error << "\n";

  std::ostringstream md;
  md << "### " << title << "\n\n`study " << cl.scene_file << "`; reference: `" << sweep.text("reference")
     << "`; error: `" << error_key << "` of summary.json.\n\n| method | " << key
     << " | particles | grid nodes | steps | wall time [s] | error |\n| --- | --- | --- | --- | --- | --- | --- |\n";
  for (const Case& c : cases)
    md << "| " << c.method << " | " << number(c.value) << " | " << number(c.particles) << " | " << number(c.nodes)
       << " | " << number(c.steps) << " | " << number(c.seconds) << " | " << number(c.error) << " |\n";
  bool orders_ok = true;
  md << "\n| method | observed order (error vs h) | error vs wall time slope | asserted |\n| --- | --- | --- | --- |\n";
  for (const Method& method : methods) {
    std::vector<double> h, t, e;
    for (const Case& c : cases)
      if (c.method == method.name) {
        h.push_back(spacing == "inverse" ? 1.0 / c.value : c.value);
        t.push_back(c.seconds);
        e.push_back(c.error);
      }
    const double order = spacing == "none" ? std::nan("") : log_slope(h, e);
    const bool ok = std::isnan(method.min_order) || order >= method.min_order;
    orders_ok = orders_ok && ok;
    md << "| " << method.name << " | " << number(order) << " | " << number(log_slope(t, e)) << " | "
       << (std::isnan(method.min_order) ? "-" : ">= " + number(method.min_order) + (ok ? " (ok)" : " (FAILED)"))
       << " |\n";
  }
  if (!notes.empty()) md << "\n" << notes << "\n";
  md << "\n![" << title << "]("
     << "study.png)\n";
  std::ofstream(out / "study.md") << md.str();
  plot(out, title, methods, cases);
  std::cout << md.str();
  if (cl.check && !orders_ok) return 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_app(argc, argv, "study", "Error against run time over a parameter sweep", run);
}
