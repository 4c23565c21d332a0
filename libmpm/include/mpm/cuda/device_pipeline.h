#pragma once
//! The solid step on a CUDA device (library mpm::cuda): a scene chooses where its explicit
//! solid step runs with
//!
//!   device: cuda              # cpu (default) | cuda
//!   device_precision: single  # double (default) | single: the particles and grid on the device
//!
//! On `cuda` the pipeline is one stage, 'device_step', that keeps the particles on the GPU and
//! runs the whole explicit step there (time step, block binning, P2G with the stress, grid
//! update with walls and colliders, G2P with the deformation update, return map and stress;
//! docs/gpu.md). The host particles are brought up to date by Pipeline::synchronize, which the
//! Runner calls at every frame end and before a checkpoint, so the frames, diagnostics,
//! checkpoints and the apps' results come from the same code as on the CPU path. Scenes share
//! the YAML, the output writers and the checks with the CPU.
//!
//! The device step covers 3D uniform-grid scenes with the quadratic B-spline, APIC, the
//! explicit solver, fixed-corotated, Neo-Hookean and Hencky elasticity with Drucker-Prager (no
//! dilatancy or rate dependence) or von Mises plasticity, domain walls and half-space, box and
//! sphere colliders (fixed or translating). Anything else under `device: cuda` is an input
//! error naming the key, before any output is written; so is a build without the CUDA
//! back-end, a machine without a GPU, or a scene whose estimated device memory exceeds three
//! quarters of the GPU's free memory (both figures in the message).
#include <mpm/core/config.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/state.h>
#include <mpm/solid/solid_scene.h>

#include <string>

namespace mpm::cuda {

struct Device {
  bool cuda = false;
  bool single_precision = false;
};

//! Reads the scene's `device` and `device_precision` keys.
Device parse_device(const Config& scene);

//! Whether this build has the CUDA back-end (SEDIMENT_WITH_CUDA).
bool built_with_cuda();
//! "" when this build has the CUDA back-end and the machine a usable GPU, else why not.
std::string unavailable_reason();

//! solid::make_solid_pipeline(solid) on the CPU; on `cuda` the pipeline of the one stage
//! 'device_step'. InputError at `scene`'s `device` key when the device cannot run the scene.
template <int dim>
Pipeline<MpmState<dim>> make_solid_pipeline(const solid::SolidScene<dim>& solid, const Device& device,
                                            const Config& scene);

}  // namespace mpm::cuda
