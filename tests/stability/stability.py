#!/usr/bin/env python3
"""The stability suite: stiff and extreme solid, fluid and coupled cases, each with its stated
expected outcome (docs/stability.md, whose header is stability_header.md).

Every case runs one app on a scene with --set overrides and must end as expected:
  completes  exit 0, no warning on stderr, no NaN or Inf in diagnostics.csv and bounded
             energy: the total energy E = kinetic + elastic + gravity potential, measured
             against the energy the run releases, S = KE(0) + elastic(0) + max_t (PE(0) -
             PE(t)) (the potential above the lowest height the bodies reach, a difference of
             potentials: the same wherever the origin is; --origin-shift shows it), must
             - never exceed E(0) by more than GROWTH = 1e-4 S (no case creates energy; the
               measured growth is 0 in every case),
             - where the case conserves energy (`conserves`: elastic bodies in free flight or at
               rest, no contact, no plasticity, no viscosity before the end), never fall below
               E(0) by more than LOSS = 2 % S (measured at most 0.84 % S, single_particle, the
               transfers' damping of one particle; 0.17 % for the block); elsewhere contact,
               plasticity, viscosity and drag dissipate, and E >= E(0) - S holds by the
               definition of S.
             No case has an inflow, so no inflow work enters S. A case with `check` also passes
             the app's own --check (a stated error, or solid_scene's energy bound);
  warns      as completes, but stderr holds warning lines with the given substrings;
  stops      exit 3 and a one-line message naming the stage, the particle or cell and the
             quantity (the given substrings);
  refused    exit 2 (input error) and a message naming the key and its accepted range.
A case that hangs past its timeout, dies by a signal or leaves NaNs fails.

    stability.py --bin BUILD/apps --work DIR [--apps a,b] [--doc docs/stability.md] [--only NAME]
    stability.py --bin BUILD/apps --work DIR --origin-shift 100 [--only NAME]

--origin-shift H runs the solid_scene cases on block_drop.yaml once more with the domain and the
bodies moved H metres up and fails unless the energy bounds (this script's and solid_scene's
energy_growth and energy_scale) come out the same as unshifted, to 1e-6 of S.

--apps lists the apps the build has (default: every app of the table); the cases of the others
are skipped and --doc then refuses to write (the table must hold every case).
"""
import argparse, csv, json, math, os, shutil, subprocess, sys, time

BASE = "data/scenes/stability/block_drop.yaml"
BLOCK = "bodies.0"
SETTLING = "data/scenes/settling.yaml"
# 16 cells across (dx = 2 mm) and 0.2 s: the steady window of --check still holds 4 frames.
SETTLING_SHORT = ["column.cells_per_width=16", "time.end=0.2", "measure.start=0.05"]
DAM_BREAK = "data/scenes/dam_break.yaml"
COLLAPSE = "data/scenes/submerged_collapse.yaml"
# A pressure solve that cannot converge: a tolerance below round-off and 3 CG iterations.
NO_CONVERGE = ["pressure.solver=cg", "pressure.tolerance=1e-30", "pressure.max_iterations=3"]
# Warned, the coupled run continues on its unconverged pressures: 3 CG iterations leave the
# mixture impulse so wrong that grains are thrown out of the grid (a correct stop at 'sort'),
# 10 leave it bounded.
NO_CONVERGE_WARN = ["pressure.solver=cg", "pressure.tolerance=1e-30", "pressure.max_iterations=10",
                    "pressure.on_failure=warn"]
PRESSURE_MESSAGE = ["pressure solver 'cg'", "did not converge", "relative residual"]


def case(name, setup, app, scene, overrides, outcome, needles=None, check=False, extra=None, conserves=False):
    """outcome: completes | warns | stops | refused; needles: substrings of the message;
    check: also pass the app's --check; extra(rows, summary) -> error text or None;
    conserves: the energy may not drop either (module docstring)."""
    return dict(name=name, setup=setup, app=app, scene=scene, overrides=overrides, outcome=outcome,
                needles=needles or [], check=check, extra=extra, conserves=conserves)


def at_rest(rows, summary):
    """max_speed 0 in every frame"""
    speed = max((float(r["max_speed"]) for r in rows), default=0.0)
    return None if speed == 0.0 else f"a block at rest moved (max speed {speed})"


def residual_recorded(rows, summary):
    """pressure_residual in (0, 1e-6) and pressure_round_off = 1 in every frame after the first"""
    # The relative tolerance 1e-30 is below round-off: the solve stops at its absolute floor
    # (1e-14 of the scale of D u, pressure_projection.cpp), diagnostics.csv records the
    # relative residual it reached and flags the frame with pressure_round_off = 1.
    res = [float(r["pressure_residual"]) for r in rows[1:]]
    flags = [r["pressure_round_off"] for r in rows[1:]]
    if not res or not all(0.0 < x < 1e-6 for x in res):
        return f"pressure_residual {res}"
    return None if all(float(f) == 1.0 for f in flags) else f"pressure_round_off {flags}"


def recovered(rows, summary):
    """the elastic energy at the end below 5 % of its peak (the body found its rest shape)"""
    elastic = [float(r["elastic_energy"]) for r in rows]
    peak = max(elastic)
    return None if elastic[-1] <= 0.05 * peak else f"elastic energy {elastic[-1]:.3g} J of a peak {peak:.3g} J"


def hundredfold_step(rows, summary):
    """at most 1/100 of the explicit steps (0.5 dx / c, c = 3670 m/s)"""
    steps = sum(int(float(r["steps"])) for r in rows)
    end = float(rows[-1]["time"])
    explicit = end / (0.5 * 0.02 / 3670.0)
    return None if steps <= explicit / 100 else f"{steps} steps against {explicit:.0f} explicit ones"


def passed_outlet(rows, summary):
    """the body passed the outlet (height of its centre of mass below 0.25 m)"""
    mass = float(rows[-1]["mass"])
    height = float(rows[-1]["gravity_potential"]) / (9.81 * mass)
    return f"centre of mass still at {height:.3g} m" if height > 0.25 else None


def passed_funnel(rows, summary):
    """the body passed the outlet (height of its centre of mass below 0.25 m) and recovered"""
    return passed_outlet(rows, summary) or recovered(rows, summary)


CASES = [
    # Solids (solid_scene --check: total energy never grows by more than 2 %).
    case("stiff_1e7", "Young's modulus 1e7 Pa, automatic time step", "solid_scene", BASE,
         ["materials.0.youngs_modulus=1e7", "time.end=0.05"], "completes", check=True, conserves=True),
    case("stiff_1e10", "Young's modulus 1e10 Pa, automatic time step (dt ~ 2e-6 s)", "solid_scene", BASE,
         ["materials.0.youngs_modulus=1e10", "time.end=0.01"], "completes", check=True, conserves=True),
    case("max_dt_10x",
         "time.max_dt 10x above the stable step: the controller subdivides, never exceeds the limit",
         "solid_scene", BASE, ["materials.0.youngs_modulus=1e7", "time.max_dt=3e-3", "time.end=0.05"],
         "completes", check=True, conserves=True),
    case("crushed_5pct", "block crushed to 5 % of its height (F = diag(1, 0.05)) and released",
         "solid_scene", BASE,
         [f"{BLOCK}.stretch=[1, 0.05]", f"{BLOCK}.lo=[0.3, 0.2]", f"{BLOCK}.hi=[0.7, 0.22]",
          "materials.0.elasticity=neo_hookean", "time.end=0.3"], "completes", check=True),
    case("inverted_fixed_corotated", "every particle starts inverted, F = diag(1, -0.5) (fixed corotated)",
         "solid_scene", BASE, [f"{BLOCK}.stretch=[1, -0.5]", "time.end=0.2"], "completes", check=True),
    # Neo-Hookean and Hencky continue their log below the critical stretch 0.1 (inversion
    # handling); an inverted particle is then ~10x stiffer than at rest, which the explicit
    # step's rest-state wave speed does not see: these cases bound the step by hand.
    case("inverted_neo_hookean", "inverted start with Neo-Hookean, time.max_dt = 1e-4 s", "solid_scene", BASE,
         [f"{BLOCK}.stretch=[1, -0.5]", "materials.0.elasticity=neo_hookean", "time.end=0.2", "time.max_dt=1e-4"],
         "completes", check=True),
    case("inverted_hencky", "inverted start with Hencky StVK, time.max_dt = 1e-4 s", "solid_scene", BASE,
         [f"{BLOCK}.stretch=[1, -0.5]", "materials.0.elasticity=hencky_stvk", "time.end=0.2", "time.max_dt=1e-4"],
         "completes", check=True),
    case("twisted_bar_3d", "3D bar held at x = 0 (sticky wall), spun about its axis at 20 rad/s",
         "solid_scene", "data/scenes/stability/twisted_bar_3d.yaml", [], "completes", check=True),
    case("impact_100ms", "block hits the floor at 100 m/s", "solid_scene", BASE,
         [f"{BLOCK}.velocity=[0, -100]", "time.end=0.02", "time.frame_dt=0.002"], "completes", check=True),
    case("leaves_domain", "the floor is open: the block falls out of the grid", "solid_scene", BASE,
         ["walls.y_min=open", "time.end=1"], "stops", ["stage 'sort'", "particle", "left the grid domain"]),
    case("single_particle", "one particle (one lattice point in the body)", "solid_scene", BASE,
         [f"{BLOCK}.lo=[0.5, 0.5]", f"{BLOCK}.hi=[0.52, 0.52]", f"{BLOCK}.particles_per_cell=1"],
         "completes", check=True, conserves=True),
    case("empty_domain", "no particles at all", "solid_scene", "data/scenes/stability/empty.yaml", [],
         "completes", check=True, conserves=True),
    case("zero_gravity", "a block at rest without gravity stays exactly at rest", "solid_scene", BASE,
         ["gravity=[0, 0]"], "completes", check=True, extra=at_rest, conserves=True),
    # The implicit solid step (solver: implicit).
    case("implicit_stiff_1e10", "Young's modulus 1e10 Pa, solver: implicit at the particle CFL step "
         "(the explicit step would be 2.7e-6 s)", "solid_scene", BASE,
         ["solver=implicit", "materials.0.youngs_modulus=1e10", "time.end=0.3"], "completes", check=True,
         extra=hundredfold_step),
] + [
    case(f"implicit_flatten_{model}", f"block crushed to 5 % of its height and released, {model}, "
         "solver: implicit", "solid_scene", BASE,
         ["solver=implicit", f"{BLOCK}.stretch=[1, 0.05]", f"{BLOCK}.lo=[0.3, 0.2]", f"{BLOCK}.hi=[0.7, 0.22]",
          f"materials.0.elasticity={model}", "time.end=0.3"], "completes", check=True, extra=recovered)
    for model in ("fixed_corotated", "neo_hookean", "hencky_stvk")
] + [
    case(f"implicit_inverted_{model}", f"every particle starts inverted, F = diag(1, -0.5), {model}, "
         "solver: implicit", "solid_scene", BASE,
         ["solver=implicit", f"{BLOCK}.stretch=[1, -0.5]", f"materials.0.elasticity={model}", "time.end=0.2"],
         "completes", check=True, extra=None if model == "fixed_corotated" else recovered)
    for model in ("fixed_corotated", "neo_hookean", "hencky_stvk")
] + [
    case("implicit_funnel_squeeze", "Neo-Hookean block (E = 2e4 Pa, 0.4 m wide) thrown at 10 m/s into a "
         "funnel whose outlet is 0.08 m wide, solver: implicit", "solid_scene", "data/scenes/stability/funnel.yaml",
         [], "completes", check=True, extra=passed_funnel),
] + [
    # Particle domains (explicit, PIC/FLIP through the corners) and their dynamic enrichment,
    # whose surfaces' self-contact keeps the folded front from locking in (user guide 4.5a).
    case(f"{name}_funnel_squeeze", f"the funnel squeeze, solver: explicit, {what}, 1.5 s", "solid_scene",
         "data/scenes/stability/funnel.yaml",
         ["solver=explicit", "transfer.scheme=flip", "particle_domains=true", "time.end=1.5"] + sets,
         "completes", check=True, extra=extra)
    for name, what, sets, extra in (
        ("domains", "particle domains", [], passed_funnel),
        ("enriched", "enriched particle domains (eps = 0.6)", ["domain_enrichment=0.6"], passed_funnel))
] + [
    # The implicit step with the enriched corners among Newton's unknowns (no self-contact: the
    # block passes but is not asked to recover).
    case("implicit_enriched_funnel_squeeze", "the funnel squeeze, solver: implicit, enriched particle domains "
         "(eps = 0.6), 1.5 s", "solid_scene", "data/scenes/stability/funnel.yaml",
         ["transfer.scheme=flip", "particle_domains=true", "domain_enrichment=0.6", "time.end=1.5"],
         "completes", check=True, extra=passed_outlet)
] + [
    case(f"enriched_flatten_{model}", f"block crushed to 5 % of its height and released, {model}, "
         "enriched particle domains (eps = 0.6)", "solid_scene", BASE,
         ["transfer.scheme=flip", "particle_domains=true", "domain_enrichment=0.6", f"{BLOCK}.stretch=[1, 0.05]",
          f"{BLOCK}.lo=[0.3, 0.2]", f"{BLOCK}.hi=[0.7, 0.22]", f"materials.0.elasticity={model}", "time.end=0.3"],
         "completes", check=True, extra=recovered)
    for model in ("fixed_corotated", "neo_hookean", "hencky_stvk")
] + [
    case("snowball", "a snowball (snow plasticity, fixed corotated) thrown at the floor at 5.7 m/s", "solid_scene",
         "data/scenes/snowball.yaml", ["output.png=false"], "completes", check=True),
    case("implicit_no_converge_stop", "solver: implicit with Newton capped at 1 iteration and tolerance "
         "1e-12, on_failure = stop", "solid_scene", BASE,
         ["solver=implicit", "implicit.max_newton_iterations=1", "implicit.tolerance=1e-12", "time.end=0.2"],
         "stops", ["stage 'implicit_update'", "Newton did not converge", "relative residual"]),
    # Fluid.
    case("density_ratio_1000", "`settling`: grains of 1000 kg/m^3 in a fluid of 1 kg/m^3 (ratio 1000), "
         "phi = 0.01, d = 0.1 mm; --check: settling speed within 10 % of the drag law's and of Richardson-Zaki's",
         "settling", SETTLING, SETTLING_SHORT + ["fluid.density=1", "sediment.density=1000",
                                                 "sediment.volume_fraction=0.01"], "completes", check=True),
    case("falling_column_wall",
         "`dam_break` column (a = 5.7 cm, 10 cells across) under gravity 10 g along +x: "
         "falls 4a freely and hits the far wall at ~7 m/s", "dam_break", DAM_BREAK,
         ["column.cells_per_width=10", "gravity=[98.1, 0]", "walls.y_max=sticky", "time.end=0.12"],
         "completes"),
    case("falling_blob", "a disc of water (r = 5 cm) falls 25 cm freely in a closed box and splashes on the "
         "floor at ~2.2 m/s (`coupled_scene`, fluid only)", "coupled_scene",
         "data/scenes/stability/falling_blob.yaml", [], "completes"),
    case("pressure_tolerance_1e-30", "`dam_break`, pressure.tolerance = 1e-30 alone: below round-off, the "
         "solve stops at its absolute floor (1e-14 of the scale of D u); the run says so once and "
         "diagnostics.csv flags every such solve and records the relative residual reached",
         "dam_break", DAM_BREAK, ["column.cells_per_width=10", "pressure.tolerance=1e-30", "time.end=0.05"],
         "warns", ["warning: stage 'pressure'", "tolerance 1e-30 is below round-off", "relative residual"],
         extra=residual_recorded),
    case("pressure_no_converge_stop", "`dam_break`, tolerance 1e-30 and 3 CG iterations, on_failure = stop",
         "dam_break", DAM_BREAK, ["column.cells_per_width=10", "time.end=0.05"] + NO_CONVERGE, "stops",
         ["stage 'pressure'"] + PRESSURE_MESSAGE),
    case("pressure_no_converge_warn", "as above with on_failure = warn: every step warns, the run completes",
         "dam_break", DAM_BREAK, ["column.cells_per_width=10", "time.end=0.05", "pressure.on_failure=warn"]
         + NO_CONVERGE, "warns", ["warning: stage 'pressure'"] + PRESSURE_MESSAGE),
    case("pressure_fallback", "`dam_break`, CG capped at 15 iterations with `pressure.fallback = mgpcg`: every "
         "failed CG solve is retried by MGPCG from the same guess and reported", "dam_break", DAM_BREAK,
         ["column.cells_per_width=10", "time.end=0.05", "pressure.solver=cg", "pressure.max_iterations=15",
          "pressure.fallback=mgpcg"], "warns",
         ["warning: stage 'pressure'", "pressure solver 'cg'", "did not converge", "retrying with 'mgpcg'"]),
    case("mixture_pressure_no_converge_stop",
         "`settling`, tolerance 1e-30 and 3 CG iterations, on_failure = stop",
         "settling", SETTLING, SETTLING_SHORT + NO_CONVERGE, "stops",
         ["stage 'mixture_pressure'"] + PRESSURE_MESSAGE),
    case("mixture_pressure_no_converge_warn", "as above with 10 CG iterations and on_failure = warn", "settling",
         SETTLING, SETTLING_SHORT + NO_CONVERGE_WARN, "warns",
         ["warning: stage 'mixture_pressure'"] + PRESSURE_MESSAGE),
    # Coupling.
    case("grains_10um", "`settling` (default scene: 32 cells, 0.5 s) with d = 10 um: Stokes relaxation time "
         "15 us, far below dt ~ 1 ms (stiff drag); --check: settling speed within 10 % of the drag law's and "
         "of Richardson-Zaki's",
         "settling", SETTLING, ["drag.grain_diameter=1e-5"], "completes", check=True),
    case("packing_limit_collapse",
         "`submerged_collapse` (dx = 1 cm) at packing_fraction 0.65 = 1 - min_fluid_fraction, "
         "the accepted maximum", "submerged_collapse", COLLAPSE,
         ["grid.dx=0.01", "sediment.packing_fraction=0.65", "time.end=0.3"], "completes"),
    case("packing_limit_settling", "`settling` at volume_fraction 0.65: its range (0, 1 - n_min) is open",
         "settling", SETTLING, SETTLING_SHORT + ["sediment.volume_fraction=0.65"], "refused",
         ["sediment.volume_fraction", "(0, 0.65)"]),
    case("near_packing_settling", "`settling` at volume_fraction 0.649, Stokes drag; --check: settling speed "
         "within 10 % of n_w^2 v_St (Richardson-Zaki is compared up to phi = 0.4)", "settling", SETTLING,
         SETTLING_SHORT + ["sediment.volume_fraction=0.649", "drag.law=stokes"],
         "completes", check=True),
]

TIMEOUT = 120  # [s] per case: a case that takes longer hangs
GROWTH = 1e-4  # of S: the most E may exceed E(0) (module docstring)
LOSS = 2e-2  # of S: the most E may fall below E(0) where the case conserves energy


def released_energy(rows):
    """S (module docstring): KE(0) + elastic(0) + the potential energy released down to the lowest
    height the bodies reach, max_t (PE(0) - PE(t)); potentials enter only as differences."""
    r0 = rows[0]
    released = max(float(r0["gravity_potential"]) - float(r["gravity_potential"]) for r in rows)
    return float(r0["kinetic_energy"]) + float(r0["elastic_energy"]) + max(released, 0.0)


def energy_change(rows):
    """(growth, loss): max and min over frames t > 0 of (E(t) - E(0)) / S (module docstring);
    growth negative where every frame dissipated; both 0 when nothing moves and nothing is
    released (E(t) = E(0) to round-off)."""
    def energy(r):
        return float(r["kinetic_energy"]) + float(r["elastic_energy"]) + float(r["gravity_potential"])
    r0 = rows[0]
    scale = released_energy(rows)
    changes = [energy(r) - energy(r0) for r in rows[1:]] or [0.0]

    def relative(change):
        # Round-off of the potential, a sum over every particle of m g.x: the precision of the
        # measurement E itself (1e-12 of |PE(0)|), not an allowance that scales the bound.
        if abs(change) <= 1e-12 * (abs(float(r0["gravity_potential"])) + scale):
            return 0.0
        return change / scale if scale > 0.0 else math.copysign(math.inf, change)
    return relative(max(changes)), relative(min(changes))


def run_case(bin_dir, work, c):
    out = os.path.join(work, c["name"])
    shutil.rmtree(out, ignore_errors=True)
    cmd = [os.path.join(bin_dir, c["app"]), c["scene"], "--out", out, "--quiet"]
    for o in c["overrides"]:
        cmd += ["--set", o]
    if c["check"]:
        cmd.append("--check")
    start = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return False, f"hang: no exit within {TIMEOUT} s", {}
    info = {"seconds": round(time.monotonic() - start, 2), "exit": p.returncode}
    if p.returncode < 0:
        return False, f"killed by signal {-p.returncode}", info
    rows = []
    path = os.path.join(out, "diagnostics.csv")
    if os.path.exists(path):
        with open(path) as f:
            rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            if not math.isfinite(float(v)):
                return False, f"non-finite {k} in diagnostics.csv frame {r['frame']}", info
    info["steps"] = sum(int(float(r["steps"])) for r in rows)
    lines = p.stderr.strip().splitlines()
    if c["outcome"] in ("completes", "warns"):
        summary_path = os.path.join(out, "summary.json")
        if p.returncode != 0 or not os.path.exists(summary_path) or not rows:
            return False, f"expected completion, got exit {p.returncode}: {p.stderr.strip()[-400:]}", info
        with open(summary_path) as f:
            summary = json.load(f)["results"]
        info["energy_growth"], info["energy_loss"] = energy_change(rows)
        if info["energy_growth"] > GROWTH:
            return False, f"energy grew by {info['energy_growth']:.3g} of the energy released (bound {GROWTH})", info
        if c["conserves"] and info["energy_loss"] < -LOSS:
            return False, (f"energy fell by {-info['energy_loss']:.3g} of the energy released in a case that "
                           f"conserves it (bound {LOSS})"), info
        warnings = [l for l in lines if l.startswith("warning:")]
        if c["outcome"] == "completes" and warnings:
            return False, f"unexpected warning: {warnings[0]}", info
        if c["outcome"] == "warns":
            warnings = [l for l in warnings if all(n in l for n in c["needles"])]
            if not warnings:
                return False, f"no warning line with {c['needles']}", info
            info["warnings"] = len(warnings)
            info["message"] = warnings[0]
        if c["extra"]:
            error = c["extra"](rows, summary)
            if error:
                return False, error, info
        for key in ("settling_velocity", "hindered_velocity"):
            if key in summary:
                info[key] = summary[key]
        return True, "completed, energy bounded", info
    message = lines[-1] if lines else ""
    info["message"] = message
    code = 3 if c["outcome"] == "stops" else 2
    if p.returncode != code:
        return False, f"expected exit {code}, got exit {p.returncode}: {message}", info
    missing = [n for n in c["needles"] if n not in message]
    if missing:
        return False, f"message lacks {missing}: {message}", info
    return True, "stopped with a diagnostic" if code == 3 else "refused with an input error", info


def expected_text(c):
    names = ", ".join(f"`{n}`" for n in c["needles"])
    check = f" and `{c['app']} --check`" if c["check"] else ""
    if c["extra"]:
        check += f"; {c['extra'].__doc__}"
    energy = f"energy growth <= {GROWTH:g} S" + (f", loss <= {LOSS:g} S" if c["conserves"] else "")
    return {"completes": f"completes, {energy}{check}",
            "warns": f"completes, {energy}, warning naming {names}",
            "stops": f"stops (exit 3) naming {names}",
            "refused": f"refused (exit 2) naming {names}"}[c["outcome"]]


def measured_text(c, ok, why, info):
    if not ok or c["outcome"] in ("stops", "refused"):
        text = info.get("message", why) if ok else why
    else:
        text = (f"growth {info['energy_growth']:.2e}, loss {info['energy_loss']:.2e}, {info['steps']} steps, "
                f"{info['seconds']:.1f} s")
        if "settling_velocity" in info:
            text += (f", settling {info['settling_velocity']:.3g} m/s"
                     f" (drag law {info['hindered_velocity']:.3g})")
        if c["outcome"] == "warns":
            text += f"; {info['warnings']} warnings, first: {info['message']}"
    return f"{'pass' if ok else 'FAIL'}: {text}"


def shifted(c, height):
    """The case with the domain and the bodies of block_drop.yaml moved `height` metres up."""
    body = {"lo": [0.3, 0.2], "hi": [0.7, 0.4]}  # block_drop.yaml
    overrides = []
    for o in c["overrides"]:
        key, _, value = o.partition("=")
        if key in (f"{BLOCK}.lo", f"{BLOCK}.hi"):
            body[key.rsplit(".", 1)[1]] = json.loads(value)
        else:
            overrides.append(o)
    up = lambda p: f"[{p[0]}, {p[1] + height}]"
    overrides += [f"domain.lo=[0, {height}]", f"domain.hi=[1, {1 + height}]",
                  f"{BLOCK}.lo={up(body['lo'])}", f"{BLOCK}.hi={up(body['hi'])}"]
    return dict(c, name=c["name"] + "_shifted", overrides=overrides)


def origin_shift(args, height):
    """--origin-shift: the energy bounds of the block_drop cases with everything `height` up."""
    failures = 0
    for c in CASES:
        if c["app"] != "solid_scene" or c["scene"] != BASE or c["outcome"] != "completes":
            continue
        if args.only and c["name"] != args.only:
            continue
        measured = []
        for variant in (c, shifted(c, height)):
            ok, why, info = run_case(args.bin, args.work, variant)
            out = os.path.join(args.work, variant["name"])
            with open(os.path.join(out, "diagnostics.csv")) as f:
                rows = list(csv.DictReader(f))
            with open(os.path.join(out, "summary.json")) as f:
                results = json.load(f)["results"]
            app_growth, app_scale = results["energy_growth"], results.get("energy_scale", math.nan)
            r0 = rows[0]
            total0 = sum(float(r0[k]) for k in ("kinetic_energy", "elastic_energy", "gravity_potential"))
            measured.append(dict(ok=ok, why=why, S=released_energy(rows), growth=info.get("energy_growth"),
                                 loss=info.get("energy_loss"), app_growth=app_growth, app_scale=app_scale,
                                 total0=total0))
        a, b = measured
        same = (a["ok"] and b["ok"] and abs(a["S"] - b["S"]) <= 1e-6 * a["S"] + 1e-300
                and all(abs(a[k] - b[k]) <= 1e-6 for k in ("growth", "loss", "app_growth"))
                and abs(a["app_scale"] - b["app_scale"]) <= 1e-6 * a["app_scale"])
        failures += not same
        print(f"{'ok  ' if same else 'FAIL'} {c['name']:34s} S {a['S']:.6g} J -> {b['S']:.6g} J; growth "
              f"{a['growth']:.3g} -> {b['growth']:.3g}; loss {a['loss']:.3g} -> {b['loss']:.3g}; solid_scene "
              f"energy_growth {a['app_growth']:.3g} -> {b['app_growth']:.3g}, energy_scale {a['app_scale']:.6g} J -> "
              f"{b['app_scale']:.6g} J (E(0) from y = 0: "
              f"{a['total0']:.4g} J -> {b['total0']:.4g} J){'' if same else '; ' + a['why'] + ' / ' + b['why']}",
              flush=True)
    sys.exit(1 if failures else 0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--doc")
    ap.add_argument("--only")
    ap.add_argument("--apps", help="comma-separated apps this build has (default: all)")
    ap.add_argument("--origin-shift", type=float, metavar="H",
                    help="rerun the block_drop cases H metres up and require the same energy bounds")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    if args.origin_shift is not None:
        origin_shift(args, args.origin_shift)
    apps = set(args.apps.split(",")) if args.apps else {c["app"] for c in CASES}
    if args.doc and (args.only or apps != {c["app"] for c in CASES}):
        sys.exit("--doc needs every case: drop --only and --apps")
    failures, lines = 0, []
    for c in CASES:
        if args.only and c["name"] != args.only:
            continue
        if c["app"] not in apps:
            print(f"skip {c['name']:34s} {c['app']} is not built")
            continue
        ok, why, info = run_case(args.bin, args.work, c)
        failures += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {c['name']:34s} {why}  {json.dumps(info)}", flush=True)
        measured = measured_text(c, ok, why, info)
        lines.append(f"| `{c['name']}` | {c['setup']} | {expected_text(c)} | {measured} |")
    if args.doc:
        with open(args.doc, "w") as f:
            with open(os.path.join(os.path.dirname(__file__), "stability_header.md")) as header:
                f.write(header.read())
            f.write("| case | setup | expected outcome | measured |\n| --- | --- | --- | --- |\n")
            f.write("\n".join(lines) + "\n")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
