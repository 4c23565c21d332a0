//! LevelSet loaders of a build with OpenVDB (SEDIMENT_WITH_OPENVDB=ON). A shared libmpm_core does
//! not link OpenVDB: the first level set dlopen()s the plugin MPM_OPENVDB_PLUGIN (libmpm_openvdb.so)
//! from the directory of libmpm_core itself, so that a process whose scene has no level set never
//! maps libopenvdb and its dependencies (blosc, boost-iostreams, ...). A static libmpm_core has
//! level_set_vdb.cpp linked in.
#include <mpm/geometry/level_set.h>

#include <mpm/core/error.h>

#include "openvdb_plugin.h"

#include <string>

#ifdef MPM_OPENVDB_PLUGIN
#include <dlfcn.h>

#include <filesystem>
#endif

namespace mpm::geometry {

namespace {

#ifdef MPM_OPENVDB_PLUGIN

//! The plugin's loaders, or why there are none.
struct LoadedPlugin {
  const detail::OpenVdbPlugin* plugin = nullptr;
  std::string failure;
};

//! dlerror(), led by the path of the plugin unless it names it already.
std::string dl_failure(const std::string& path) {
  const char* text = dlerror();
  const std::string reason = text ? text : "no reason given";
  return reason.find(path) == std::string::npos ? path + ": " + reason : reason;
}

//! Loads the plugin beside libmpm_core. Never unloaded: the grids it makes keep their code there.
//! RTLD_LOCAL keeps OpenVDB's symbols out of the process-wide namespace; the plugin's own
//! dependency on libmpm_core resolves to the copy already loaded, so both share one InputError.
LoadedPlugin load_plugin() {
  Dl_info core{};
  if (dladdr(reinterpret_cast<void*>(&load_plugin), &core) == 0 || core.dli_fname == nullptr)
    return {nullptr, "dladdr cannot tell where libmpm_core is"};
  const std::string path = std::filesystem::absolute(core.dli_fname).replace_filename(MPM_OPENVDB_PLUGIN).string();
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) return {nullptr, dl_failure(path)};
  using EntryPoint = const detail::OpenVdbPlugin* (*)();
  const auto entry = reinterpret_cast<EntryPoint>(dlsym(handle, detail::kOpenVdbPluginEntryPoint));
  if (entry == nullptr) {
    const std::string failure = dl_failure(path);
    dlclose(handle);
    return {nullptr, failure};
  }
  const detail::OpenVdbPlugin* plugin = entry();
  if (plugin->version != detail::kOpenVdbPluginVersion) {
    const std::string failure = path + " has interface version " + std::to_string(plugin->version) +
                                ", this libmpm_core needs " + std::to_string(detail::kOpenVdbPluginVersion) +
                                " (the plugin of another build)";
    dlclose(handle);
    return {nullptr, failure};
  }
  return {plugin, ""};
}

const detail::OpenVdbPlugin& openvdb(const std::string& file) {
  static const LoadedPlugin loaded = load_plugin();  // once per process; thread-safe initialisation
  if (loaded.plugin == nullptr)
    throw InputError(file + ": a level-set obstacle needs the OpenVDB plugin, which did not load: " + loaded.failure +
                     " (a build configured with -DSEDIMENT_WITH_OPENVDB=ON builds " + MPM_OPENVDB_PLUGIN +
                     " and installs it beside libmpm_core)");
  return *loaded.plugin;
}

#else

const detail::OpenVdbPlugin& openvdb(const std::string&) { return *mpm_openvdb_plugin(); }

#endif

}  // namespace

LevelSet LevelSet::from_vdb(const std::string& file, const std::string& grid_name) {
  return LevelSet(openvdb(file).from_vdb(file, grid_name));
}

LevelSet LevelSet::from_mesh(const std::string& file, double voxel_size, double half_width) {
  return LevelSet(openvdb(file).from_mesh(file, voxel_size, half_width));
}

}  // namespace mpm::geometry
