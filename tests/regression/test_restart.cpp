// Restart: a run continued from a checkpoint reaches the same bits as the run that was never
// interrupted, for a solid app (column collapse, one phase), a solid on an adaptive grid (the
// adaptive jello: the tree is rebuilt from the particles' levels every step; the adaptive
// column collapse: particles split and merge every step) and a coupled one
// (settling: fluid and sediment, one checkpoint holding both; the 3D pier scour, whose
// pressure multigrid is kept between solves within a frame). The run writes 10 frames with checkpoint_every
// = 4; a copy of its output folder loses every file written after frame 4 (as if the run had
// died there) and is continued with --restart checkpoint_0004.h5. Then every particle channel
// of every phase of the later checkpoints (mpm::io::load_checkpoint into particles that declare
// the solid channels where the app's scene does) and every dataset of the
// later <series>_NNNN.h5 (HDF5 C API) must be equal bit for bit, the .xdmf files byte for
// byte, and diagnostics.csv row for row (17 significant digits, so equal text is equal bits)
// except the seconds_* timings.
#include <mpm/io/checkpoint.h>
#include <mpm/solid/solid_channels.h>

#include <doctest/doctest.h>
#include <hdf5.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

const fs::path kWork = RESTART_WORK_DIR;
constexpr int kFrames = 10, kCheckpointEvery = 4;

//! An app and its reduced scene: 10 frames of frame_dt, the phases of its checkpoints, those of
//! solid particles (which carry the solid channels), the particle series they are written to,
//! and the results that depend on the final state only (duration-like results also depend on
//! the history before the restart).
struct RestartCase {
  std::string app, scene, sets;
  double frame_dt;
  std::vector<std::string> phases, solid_phases, series, final_results;
  bool adaptive = false;       //!< solid particles carry their level (channel "level")
  bool plastic = false;        //!< solid particles carry the stress cache (a plastic material)
  bool dilatant = false;       //!< solid particles carry the rest packing (a dilatant sand)
  bool rest_position = false;  //!< solid particles carry their rest position (solid_scene rest_state)
  int dim = 2;                 //!< of the scene
};

const RestartCase kColumnCollapse{COLUMN_COLLAPSE_APP,
                                  "column_collapse.yaml",
                                  "--set column.cells_per_width=10",
                                  0.02,
                                  {""},
                                  {""},
                                  {"particles"},
                                  {"runout", "final_height", "normalized_runout"},
                                  false,
                                  true};
// Resampling splits and merges particles every step (random split rotations hashed from the
// step): the restarted run must split and merge the same particles.
const RestartCase kColumnAdaptive{COLUMN_COLLAPSE_APP,
                                  "column_collapse_adaptive.yaml",
                                  "--set column.cells_per_width=20",
                                  0.02,
                                  {""},
                                  {""},
                                  {"particles"},
                                  {"runout", "final_height", "normalized_runout"},
                                  true,
                                  true};
// Resampled by the particles' travel: the restarted run must carry the travel since the last
// resampling and resample at the same steps.
const RestartCase kColumnAdaptiveTravel = [] {
  RestartCase travel = kColumnAdaptive;
  travel.sets += " --set adaptive.resample.max_travel=0.0025";
  return travel;
}();
#ifdef JELLO_COLLIDE_APP
// Every result of jello_collide compares the end with the start of the run: none is final-only.
const RestartCase kJelloAdaptive{
    JELLO_COLLIDE_APP, "jello_collide_adaptive.yaml", "", 0.004, {""}, {""}, {"particles"}, {}, true};
#endif
// Particle domains: the particles follow their domain corners, which checkpoints store beside
// the stages' data; a restart that lost them would move every particle back.
const RestartCase kFlattenDomains{SOLID_SCENE_APP, "flatten_recover.yaml", "",    0.05,  {""},  {""},
                                  {"particles"},   {"rest_state_error"},   false, false, false, true};
// Enriched: the corner flags are decided again from F at each step, so the checkpoint needs
// nothing more (at the checkpoint, frame 4, most particles are enriched).
const RestartCase kFlattenEnriched{SOLID_SCENE_APP,
                                   "flatten_recover.yaml",
                                   "--set domain_enrichment=0.6",
                                   0.05,
                                   {""},
                                   {""},
                                   {"particles"},
                                   {"rest_state_error"},
                                   false,
                                   false,
                                   false,
                                   true};
#ifdef SETTLING_APP
// Discrete grains (no sediment material): no phase is solid.
const RestartCase kSettling{SETTLING_APP,
                            "settling.yaml",
                            "--set column.cells_per_width=16 --set measure.start=0",
                            0.01,
                            {"fluid", "sediment"},
                            {},
                            {"fluid", "sediment"},
                            {"terminal_velocity_stokes", "hindered_velocity"}};
#endif

#ifdef SUBMERGED_COLLAPSE_APP
// Dilatant continuum sediment that switches to discrete grains, under a liquid.
const RestartCase kSubmergedCollapse{SUBMERGED_COLLAPSE_APP,
                                     "submerged_collapse.yaml",
                                     "--set grid.dx=0.01 --set walls.thickness=0.01",
                                     0.02,
                                     {"fluid", "sediment"},
                                     {"sediment"},
                                     {"fluid", "sediment"},
                                     {"runout", "deposit_runout", "final_height"},
                                     false,
                                     true,
                                     true};
#endif

#ifdef SEDIMENT_TRANSPORT_APP
// 3D, fluid and sediment: the 3D pressure multigrid keeps its hierarchy from solve to solve
// within a frame (pressure.setup_reuse) and drops it at frame ends, where restarts begin. The
// bed is released at the second frame's end and carries bed load (a morphological factor that
// makes the drift matter) before and after the checkpoint the restart starts from.
const RestartCase kPierScour{SEDIMENT_TRANSPORT_APP,
                             "sediment_transport_3d.yaml",
                             "--set sediment.hold_until=0.012 --set bed_load.morphological_factor=100",
                             0.006,
                             {"fluid", "sediment"},
                             {"sediment"},
                             {"fluid", "sediment"},
                             {},
                             false,
                             true,
                             false,
                             false,
                             3};
// 2D, the flagship's flume: the bed is released at 0.05 s (within the third frame, before the
// checkpoint at 0.08 s) and carries bed load
// (the stages of coupling/bed_load.h read the bed surface and the current afresh each step) on
// both sides of the checkpoint.
const RestartCase kPipelineScour{SEDIMENT_TRANSPORT_APP,
                                 "sediment_transport.yaml",
                                 "--set sediment.hold_until=0.05 --set bed_load.morphological_factor=100",
                                 0.02,
                                 {"fluid", "sediment"},
                                 {"sediment"},
                                 {"fluid", "sediment"},
                                 {},
                                 false,
                                 true};
#endif

//! Runs the case's app; its stderr goes to <out>.log. Returns the exit status.
int run_app(const RestartCase& c, const fs::path& out, const std::string& extra) {
  const std::string command =
      "'" + c.app + "' '" + SEDIMENT_DATA_DIR + "/scenes/" + c.scene + "' --quiet " + c.sets +
      " --set time.frame_dt=" + std::to_string(c.frame_dt) + " --set time.end=" + std::to_string(kFrames * c.frame_dt) +
      " --set output.png=false" + " --set output.checkpoint_every=" + std::to_string(kCheckpointEvery) +
      " --set output.checkpoints_kept=3 --out '" + out.string() + "' " + extra + " 2> '" + out.string() + ".log'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE_MESSAGE(in, "cannot read " << path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  for (std::string field; std::getline(s, field, ',');) fields.push_back(field);
  return fields;
}

template <int dim>
void check_checkpoints_equal(const fs::path& a, const fs::path& b, const std::string& phase, bool solid,
                             const RestartCase& app) {
  const bool adaptive = app.adaptive, plastic = app.plastic;
  INFO(a.filename().string() << " phase '" << phase << "'");
  mpm::io::CheckpointHeader ha, hb;
  mpm::Particles<dim> pa, pb;
  if (solid) {
    mpm::solid::add_solid_channels(pa);
    mpm::solid::add_solid_channels(pb);
    if (plastic) {
      mpm::solid::add_stress_cache(pa);
      mpm::solid::add_stress_cache(pb);
    }
    if (app.dilatant) {
      mpm::solid::add_rest_packing(pa);
      mpm::solid::add_rest_packing(pb);
    }
    if (app.rest_position)
      for (mpm::Particles<dim>* p : {&pa, &pb})
        p->template add_channel<mpm::Vec<dim>>("rest_position", mpm::Vec<dim>::Zero(), mpm::ChannelUse{false, true});
  }
  if (adaptive)
    for (mpm::Particles<dim>* p : {&pa, &pb})
      p->template add_channel<std::uint16_t>("level", 0, mpm::ChannelUse{true, true, ""});
  mpm::io::load_checkpoint<dim>(a, ha, pa, phase);
  mpm::io::load_checkpoint<dim>(b, hb, pb, phase);
  CHECK(ha.frame == hb.frame);
  CHECK(ha.step == hb.step);
  CHECK(std::memcmp(&ha.time, &hb.time, sizeof(double)) == 0);
  CHECK(std::memcmp(&ha.dt_previous, &hb.dt_previous, sizeof(double)) == 0);
  REQUIRE(pa.size() > 0);
  CHECK(pa.has_channel("F") == solid);
  // Every channel, the kinematic and the solid ones, in the same order in both and equal in all
  // bits (NaN payloads and -0 included).
  std::vector<std::string> names;
  std::vector<std::vector<unsigned char>> bytes;
  pa.for_each_channel([&](const mpm::ChannelInfo& info, const auto& values) {
    const auto* first = reinterpret_cast<const unsigned char*>(values.data());
    names.push_back(info.name);
    bytes.emplace_back(first, first + values.size() * sizeof(values[0]));
  });
  std::size_t c = 0;
  pb.for_each_channel([&](const mpm::ChannelInfo& info, const auto& values) {
    REQUIRE(c < names.size());
    INFO("channel " << info.name);
    const auto* first = reinterpret_cast<const unsigned char*>(values.data());
    CHECK(info.name == names[c]);
    CHECK(std::vector<unsigned char>(first, first + values.size() * sizeof(values[0])) == bytes[c]);
    ++c;
  });
  CHECK(c == names.size());
}

//! Names of the datasets in the root group of an open HDF5 file.
std::vector<std::string> dataset_names(hid_t file) {
  std::vector<std::string> names;
  H5Literate(
      file, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

//! The raw bytes of a dataset in its native memory type.
std::vector<unsigned char> dataset_bytes(hid_t file, const std::string& name) {
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  REQUIRE_MESSAGE(set >= 0, "cannot open dataset " << name);
  const hid_t space = H5Dget_space(set), stored = H5Dget_type(set);
  const hid_t native = H5Tget_native_type(stored, H5T_DIR_ASCEND);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)) * H5Tget_size(native));
  if (!bytes.empty()) CHECK(H5Dread(set, native, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()) >= 0);
  H5Tclose(native);
  H5Tclose(stored);
  H5Sclose(space);
  H5Dclose(set);
  return bytes;
}

void check_particle_files_equal(const fs::path& a, const fs::path& b) {
  INFO(a.filename().string());
  const hid_t fa = H5Fopen(a.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t fb = H5Fopen(b.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(fa >= 0);
  REQUIRE(fb >= 0);
  const std::vector<std::string> names = dataset_names(fa);
  CHECK(names.size() >= 6);
  CHECK(names == dataset_names(fb));
  for (const std::string& name : names) {
    INFO("dataset " << name);
    CHECK(dataset_bytes(fa, name) == dataset_bytes(fb, name));
  }
  H5Fclose(fa);
  H5Fclose(fb);
}

//! The frame number NNNN of "<stem>_NNNN.<ext>", or -1.
int frame_of(const fs::path& file) {
  static const std::regex numbered(R"(.*_(\d{4})\.[a-z0-9]+)");
  std::smatch m;
  const std::string name = file.filename().string();
  return std::regex_match(name, m, numbered) ? std::stoi(m[1]) : -1;
}

std::string numbered(const std::string& stem, int frame, const std::string& ext) {
  char name[64];
  std::snprintf(name, sizeof name, "%s_%04d%s", stem.c_str(), frame, ext.c_str());
  return name;
}

void check_particle_state(const RestartCase& c, const fs::path& full, const fs::path& restarted) {
  for (const int frame : {2 * kCheckpointEvery, kFrames})
    for (const std::string& phase : c.phases) {
      const bool solid = std::find(c.solid_phases.begin(), c.solid_phases.end(), phase) != c.solid_phases.end();
      (c.dim == 2 ? check_checkpoints_equal<2>
                  : check_checkpoints_equal<3>)(full / numbered("checkpoint", frame, ".h5"),
                                                restarted / numbered("checkpoint", frame, ".h5"), phase, solid, c);
    }
  for (const std::string& series : c.series) {
    for (int frame = kCheckpointEvery + 1; frame <= kFrames; ++frame) {
      check_particle_files_equal(full / numbered(series, frame, ".h5"), restarted / numbered(series, frame, ".h5"));
      CHECK(read_text(full / numbered(series, frame, ".xdmf")) ==
            read_text(restarted / numbered(series, frame, ".xdmf")));
    }
    CHECK(read_text(full / (series + ".xdmf")) == read_text(restarted / (series + ".xdmf")));
  }
}

void check_diagnostics_equal_but_timings(const fs::path& full, const fs::path& restarted) {
  std::stringstream a(read_text(full / "diagnostics.csv")), b(read_text(restarted / "diagnostics.csv"));
  std::string line_a, line_b;
  REQUIRE(std::getline(a, line_a));
  REQUIRE(std::getline(b, line_b));
  const std::vector<std::string> columns = split(line_a);
  REQUIRE(line_a == line_b);
  int rows = 0;
  while (std::getline(a, line_a)) {
    REQUIRE_MESSAGE(std::getline(b, line_b), "the restarted run has fewer rows");
    const std::vector<std::string> fa = split(line_a), fb = split(line_b);
    REQUIRE(fa.size() == columns.size());
    REQUIRE(fb.size() == columns.size());
    for (std::size_t c = 0; c < columns.size(); ++c)
      if (columns[c].rfind("seconds_", 0) != 0)
        CHECK_MESSAGE(fa[c] == fb[c], "row " << rows << " column " << columns[c]);
    ++rows;
  }
  CHECK_FALSE(std::getline(b, line_b));
  CHECK(rows == kFrames + 1);
}

void check_final_results_equal(const RestartCase& c, const fs::path& full, const fs::path& restarted) {
  const auto a = nlohmann::json::parse(read_text(full / "summary.json"))["results"];
  const auto b = nlohmann::json::parse(read_text(restarted / "summary.json"))["results"];
  for (const std::string& key : c.final_results) {
    INFO(key);
    CHECK(a.at(key).get<double>() == b.at(key).get<double>());
  }
}

void check_restart(const RestartCase& c, const std::string& name) {
  const fs::path full = kWork / name / "uninterrupted", restarted = kWork / name / "restarted";
  fs::remove_all(kWork / name);
  fs::create_directories(kWork / name);
  REQUIRE_MESSAGE(run_app(c, full, "") == 0, read_text(full.string() + ".log"));

  // The copy loses what the run wrote after frame 4: later frames, checkpoints and the summary.
  fs::copy(full, restarted, fs::copy_options::recursive);
  std::vector<fs::path> later;
  for (const auto& entry : fs::directory_iterator(restarted))
    if (frame_of(entry.path()) > kCheckpointEvery || entry.path().filename() == "summary.json")
      later.push_back(entry.path());
  for (const fs::path& file : later) fs::remove(file);
  REQUIRE_FALSE(fs::exists(restarted / numbered("checkpoint", kFrames, ".h5")));
  const fs::path checkpoint = restarted / numbered("checkpoint", kCheckpointEvery, ".h5");
  REQUIRE_MESSAGE(run_app(c, restarted, "--restart '" + checkpoint.string() + "'") == 0,
                  read_text(restarted.string() + ".log"));

  check_particle_state(c, full, restarted);
  check_diagnostics_equal_but_timings(full, restarted);
  check_final_results_equal(c, full, restarted);
}

}  // namespace

TEST_CASE("a run continued from a checkpoint is bit-identical to the uninterrupted run") {
  SUBCASE("solid: column collapse") { check_restart(kColumnCollapse, "column_collapse"); }
  SUBCASE("solid on an adaptive grid with resampling: column collapse") {
    check_restart(kColumnAdaptive, "column_collapse_adaptive");
  }
  SUBCASE("solid on an adaptive grid resampled by travel: column collapse") {
    check_restart(kColumnAdaptiveTravel, "column_collapse_adaptive_travel");
  }
  SUBCASE("solid with particle domains: flatten and recover") { check_restart(kFlattenDomains, "flatten_domains"); }
  SUBCASE("solid with enriched particle domains: flatten and recover") {
    check_restart(kFlattenEnriched, "flatten_enriched");
  }
#ifdef JELLO_COLLIDE_APP
  SUBCASE("solid on an adaptive grid: jello collide") { check_restart(kJelloAdaptive, "jello_adaptive"); }
#endif
#ifdef SETTLING_APP
  SUBCASE("coupled: settling column (fluid and sediment)") { check_restart(kSettling, "settling"); }
#endif
#ifdef SEDIMENT_TRANSPORT_APP
  SUBCASE("coupled 3D: pier scour (the pressure multigrid kept within frames)") {
    check_restart(kPierScour, "pier_scour");
  }
  SUBCASE("coupled 2D: pipeline scour with bed load") { check_restart(kPipelineScour, "pipeline_scour"); }
#endif
#ifdef SUBMERGED_COLLAPSE_APP
  SUBCASE("coupled: dilatant sediment, continuum and discrete, under a liquid") {
    check_restart(kSubmergedCollapse, "submerged_collapse");
  }
#endif
}
