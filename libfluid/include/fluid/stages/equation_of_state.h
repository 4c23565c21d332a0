#pragma once
//! The stages of a weakly compressible fluid (solver/weakly_compressible_solver.h): the liquid
//! carries its volume ratio J = V / V^0 per particle, its pressure follows from J by the Tait
//! equation of state (Monaghan 1994; Becker & Teschner 2007, eq. 7), and the pressure acts as a
//! particle stress, so no linear system is solved: the time step resolves the speed of sound.
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <string>
#include <vector>

namespace fluid {

//! p(J) = B ((rho / rho_0)^gamma - 1) with rho / rho_0 = 1 / J and B = rho_0 c^2 / gamma, so that
//! c is the speed of sound at rest. A stretched liquid (J > 1) holds no tension: p = 0 there, so
//! a free surface and spray are stress-free.
struct TaitEquationOfState {
  double density = 1000.0;       //!< rho_0 [kg/m^3]
  double speed_of_sound = 20.0;  //!< c [m/s]; about 10x the fastest flow keeps |rho / rho_0 - 1| near 1 %
  double exponent = 7.0;         //!< gamma [-]
  double pressure(double J) const;
};

//! The name of the volume ratio channel (double, 1 at rest; written to frames, checkpointed).
inline constexpr const char* kVolumeRatio = "volume_ratio";
//! The name of the liquid volume ratio channel of a liquid in a sediment's pores (double,
//! checkpointed; advanced by the coupling, coupling/stages/pore_pressure.h): V_own / V^0, the
//! ratio its pressure follows, while volume_ratio (J) follows the mixture volume the particle
//! stands for. A clear liquid has no such channel: its own volume ratio is J.
inline constexpr const char* kLiquidVolumeRatio = "liquid_volume_ratio";

//! The volume ratio each particle's pressure follows: liquid_volume_ratio where the particles
//! carry it, else volume_ratio.
template <int dim>
const std::vector<double>& own_volume_ratio(const mpm::Particles<dim>& P) {
  if (const std::vector<double>* own = P.template find_channel<double>(kLiquidVolumeRatio)) return *own;
  return P.template channel<double>(kVolumeRatio);
}

namespace stages {

//! Grid forces of the pressure: f_i = - sum_p V_p^0 tau_p grad w_ip with the Kirchhoff stress
//! tau_p = -p(J_own,p) J_p I (mpm::stress_to_grid_forces; J_own = own_volume_ratio, J itself
//! for a clear liquid). Precondition: particles sorted.
template <int dim>
class EquationOfStateForces final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  explicit EquationOfStateForces(TaitEquationOfState eos) : eos_(eos) {}
  std::string name() const override { return "pressure_forces"; }
  std::vector<std::string> reads() const override {
    return {"particle.order", "grid.blocks", "particle.x", "particle.volume0", "particle.volume_ratio"};
  }
  std::vector<std::string> writes() const override { return {"grid.force"}; }
  void run(mpm::MpmState<dim>& s) override;

private:
  TaitEquationOfState eos_;
  std::vector<mpm::Mat<dim>> weighted_stress_;
};

//! The walls' push on the liquid. The weak form of the momentum balance carries the boundary
//! term of the wall, the integral of p w_i n over the wall's face; the particle sum of
//! EquationOfStateForces covers only the liquid, so a free node whose stencil crosses a wall
//! keeps a force of about p w_i(wall) per unit area toward the wall that nothing balances (a
//! tank at rest then compresses the liquid next to its walls to 1.6 rho g h). Each particle
//! within a kernel's reach of a closed wall's plane (the inner face of the wall layer) gets an
//! image mirrored across it, with the particle's volume and the pressure at the wall point x_w
//! below it, extrapolated hydrostatically as for the fixed walls of Adami, Hu & Adams (2012,
//! eq. 27):
//!   p_w = max(0, p_p + (rho_0 / J_p) g . (x_w - x_p)),   f_ia += V_p^0 J_p p_w d_a w_i(x')
//! along the wall's axis a only, on the nodes strictly on the liquid's side of the plane (the
//! nodes on or behind it carry the wall's condition). Held constant over the image, p_w gives
//! p_w w_i(wall), the boundary term: the images continue the particles' lattice, and the sum of
//! d_a w_i over a whole lattice vanishes, so a liquid at rest along a wall is balanced as in the
//! interior. Colliders other than the domain walls get no images.
template <int dim>
class WallPressureForces final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  WallPressureForces(TaitEquationOfState eos, mpm::geometry::DomainWalls<dim> walls)
      : eos_(eos), walls_(std::move(walls)) {}
  std::string name() const override { return "wall_pressure"; }
  std::vector<std::string> reads() const override {
    return {"grid.blocks", "grid.force", "particle.x", "particle.volume0", "particle.volume_ratio"};
  }
  std::vector<std::string> writes() const override { return {"grid.force"}; }
  void run(mpm::MpmState<dim>& s) override;

private:
  struct Push {  //!< one image's force on one node along its wall's axis [N]
    mpm::Index node;
    int axis;
    double force;
  };
  TaitEquationOfState eos_;
  mpm::geometry::DomainWalls<dim> walls_;
  std::vector<std::vector<Push>> pushes_;  //!< per fixed chunk of particles
};

//! J_p <- det(I + dt grad v_p) J_p with grad v_p = sum_i v_i (grad w_ip)^T from the final grid
//! velocities (the determinant of the deformation update of a solid). NumericalError when a
//! particle is compressed through zero volume (a step far above the acoustic limit).
template <int dim>
class VolumeRatioUpdate final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  std::string name() const override { return "volume_ratio"; }
  std::vector<std::string> reads() const override {
    return {"grid.velocity", "particle.order", "particle.volume_ratio"};
  }
  std::vector<std::string> writes() const override { return {"particle.volume_ratio"}; }
  void run(mpm::MpmState<dim>& s) override;
  //! density_deviation: max_p |1 / J_p - 1| over the compressed particles, the error of the
  //! weakly compressible model against an incompressible liquid.
  std::vector<mpm::Diagnostic> diagnostics() const override { return {{"density_deviation", deviation_}}; }

private:
  std::vector<mpm::Mat<dim>> grad_v_;
  double deviation_ = 0.0;
};

}  // namespace stages
}  // namespace fluid
