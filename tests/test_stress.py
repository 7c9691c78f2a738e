"""Stress recovery (outputs.stress) against CalculiX on the builder's own mesh, and against beam
theory.

The FMU's stress outputs at static equilibrium (static_start, loads held) are compared with
CalculiX's linear static solution of the same deck (`--export-inp`: same nodes, elements,
material, flanges as *RIGID BODY), in two ways (ccx_stress.py):

- with CalculiX's integration-point stresses (*EL PRINT, 7 digits) extrapolated to the nodes
  with the exact matrices and averaged as CalculiX averages: the same definition as ours;
- with CalculiX's own nodal stresses (.frd), whose extrapolation tables are rounded to 3..5
  decimals and whose values carry 6 digits: bounded by that rounding.

Run with -s to see the measured deviations."""

import json
import math
import zipfile

import numpy as np
import pytest

import calculix as ccx
import ccx_stress
from conftest import EXAMPLES, run_builder
from test_calculix import build_with_deck
from fmu_access import Fmu

COMPONENTS = ["sxx", "syy", "szz", "sxy", "syz", "szx"]


def build(spec: dict, workdir, name: str):
    """Build `spec` with its CalculiX deck in workdir/name: (FMU path, report, deck text)."""
    folder = workdir / name
    folder.mkdir()
    path = folder / f"{name}.json"
    path.write_text(json.dumps(spec))
    return build_with_deck(path, folder)


def fmu_static_stresses(fmu_path, report, inputs: dict) -> np.ndarray:
    """The FMU's stress outputs (points x 6) at the static equilibrium under `inputs`."""
    fmu = Fmu(fmu_path, "ModelExchange")
    try:
        fmu.set(static_start=True, **inputs)
        fmu.initialize()
        names = [f"{p['name']}.{c}" for p in report["stress_points"] for c in COMPONENTS]
        return fmu.get(*names).reshape(-1, 6)
    finally:
        fmu.close()


def deck_nodes_of(report, deck) -> list[int]:
    """The deck's node id of every recovery point (the deck numbers nodes its own way: matched
    by coordinates, which the deck carries to 17 digits)."""
    coords = ccx.node_coordinates(deck)
    ids = np.array(list(coords))
    xyz = np.array([coords[i] for i in ids])
    out = []
    for p in report["stress_points"]:
        d = np.linalg.norm(xyz - np.array(p["position"]), axis=1)
        assert d.min() <= 1e-12 * (1 + np.abs(xyz).max()), f"{p['name']}: no deck node at {p['position']}"
        out.append(int(ids[d.argmin()]))
    return out


def compare(label, ours, reference, tol):
    """Largest deviation per point relative to that point's largest component; asserts `tol`."""
    assert ours.shape == reference.shape, (ours.shape, reference.shape)
    scale = np.abs(reference).max(axis=1)
    worst = (np.abs(ours - reference).max(axis=1) / scale)
    print(f"  {label}: {len(worst)} points, largest deviation {worst.max():.2e} of the point's largest "
          f"component (tolerance {tol:.0e})")
    assert worst.max() <= tol, f"{label}: point {worst.argmax()} deviates {worst.max():.2e}"
    return worst.max()


def check_against_calculix(fmu, report, deck, workdir, fmu_inputs: dict, ccx_loads: str, label: str,
                           tol_points: float, tol_frd: float):
    nodes = deck_nodes_of(report, deck)
    analysis = (ccx.rigid_body(deck, "base") + ccx.rigid_body(deck, report["flanges"][1]["name"])
                + ccx.clamp(deck, "base") + ccx_stress.stress_step(ccx_loads))
    result = ccx.run_ccx(deck, analysis, workdir / label)
    ours = fmu_static_stresses(fmu, report, fmu_inputs)
    at_points = ccx_stress.el_print_stresses(result.dat)
    exact = ccx_stress.nodal_from_points(deck, at_points, nodes)
    frd = ccx_stress.frd_nodal_stresses((workdir / label / "job.frd").read_text())
    print(f"\n{label}:")
    compare("vs CalculiX integration-point stresses, extrapolated exactly",
            ours, np.array([exact[n] for n in nodes]), tol_points)
    compare("vs CalculiX nodal stresses (.frd)", ours, np.array([frd[n] for n in nodes]), tol_frd)
    return ours


def beam_spec(**scene):
    spec = json.loads((EXAMPLES / "beam.json").read_text())
    spec.pop("$schema")
    spec["outputs"] = {"stress": {"points": [[0.1, 0.005, 0.01], [0.5, 0.0, 0.01], [0.3, -0.005, 0.0]],
                                  "hot_spots": 4}}
    if scene:
        spec["scene"] = scene
    return spec


#: Tolerances, about ten times what these meshes measure (-s prints it). The exact comparison is
#: bounded by CalculiX's printed integration-point stresses: 7 digits (5e-7) amplified by the
#: extrapolation rows, whose |entries| sum to 9.1 for C3D20's 27-point fit and 2.9 for C3D10:
#: measured 7.1e-6 (C3D20) and 9.8e-7 (C3D10). Its .frd nodal stresses carry 6 digits and
#: come from tables rounded to 3..5 decimals: measured 1.9e-5 .. 3.5e-5.
TOL_POINTS_HEX20 = 1e-4
TOL_POINTS_TET10 = 1e-5
TOL_FRD = 3e-4


def test_beam_hex20_flange_loads_and_gravity_vs_calculix(tmp_path):
    from fmpy.validation import validate_fmu

    fmu, report, deck = build(beam_spec(loads=["gravity"]), tmp_path, "beam")
    assert len(report["stress_points"]) == 7
    # modelDescription.xml with 49 stress outputs, their units and dependencies, is valid
    assert validate_fmu(str(fmu)) == []
    tip = ccx.cload(deck, "tip", force=(0.0, 2.0, 5.0), moment=(0.3, 0.0, 0.1))
    check_against_calculix(fmu, report, deck, tmp_path,
                           {"tip.f[2]": 2.0, "tip.f[3]": 5.0, "tip.t[1]": 0.3, "tip.t[3]": 0.1},
                           tip, "beam, tip loads", TOL_POINTS_HEX20, TOL_FRD)
    check_against_calculix(fmu, report, deck, tmp_path, {"g[3]": -9.81},
                           ccx.gravity(9.81, (0, 0, -1)), "beam, gravity", TOL_POINTS_HEX20, TOL_FRD)


def test_beam_bending_stress_vs_beam_theory(tmp_path):
    """sigma_xx = -F (L - x) z / I at x = 0.1 m and 0.5 m, top fibre (z = h/2), under a tip force
    F_z: five beam heights from the clamp, where Saint-Venant's principle lets beam theory hold
    (nearer, the rigid clamp's restraint of the Poisson contraction adds its local stresses)."""
    fmu, report, _ = build(beam_spec(), tmp_path, "beam")
    s = fmu_static_stresses(fmu, report, {"tip.f[3]": 1.0})
    b, h, length = 0.01, 0.02, 1.0
    inertia = b * h**3 / 12
    for k, x in [(0, 0.1), (1, 0.5)]:
        assert report["stress_points"][k]["position"][0] == pytest.approx(x, abs=1e-12)
        theory = -1.0 * (length - x) * (h / 2) / inertia
        print(f"\n  x = {x}: sigma_xx {s[k, 0]:.6e} Pa, beam theory {theory:.6e} Pa, "
              f"deviation {abs(s[k, 0] / theory - 1):.2e}")
        # measured 6.5e-5 at x = 0.1 m (the clamp's local stresses fading) and 6e-10 at 0.5 m;
        # beam theory's own error (shear, Poisson) on this slender beam is that small, far
        # below the 2 % the issue asks
        assert abs(s[k, 0] / theory - 1) <= 1e-3


def test_bracket_tet10_vs_calculix(tmp_path):
    spec = json.loads((EXAMPLES / "bracket" / "bracket-inp.json").read_text())
    spec.pop("$schema", None)
    spec["geometry"]["mesh"] = str((EXAMPLES / "bracket" / spec["geometry"]["mesh"]).resolve())
    spec["scene"] = {"loads": ["gravity"]}
    spec["outputs"] = {"stress": {"points": [[0.03, 0.02, 0.003], [0.003, 0.02, 0.02]], "hot_spots": 6}}
    fmu, report, deck = build(spec, tmp_path, "bracket")
    arm = report["flanges"][1]["name"]
    loads = ccx.cload(deck, arm, force=(10.0, 0.0, -20.0), moment=(0.0, 0.5, 0.0))
    check_against_calculix(fmu, report, deck, tmp_path,
                           {f"{arm}.f[1]": 10.0, f"{arm}.f[3]": -20.0, f"{arm}.t[2]": 0.5},
                           loads, "bracket, arm loads", TOL_POINTS_TET10, TOL_FRD)
    check_against_calculix(fmu, report, deck, tmp_path, {"g[1]": 9.81},
                           ccx.gravity(9.81, (1, 0, 0)), "bracket, gravity", TOL_POINTS_TET10, TOL_FRD)


def test_hot_spots_are_the_peaks_of_the_unit_cases(tmp_path):
    """Every hot spot is the peak of a unit case over all nodes not tied to a flange, by the
    builder's own report of static stresses (a consistency check of the ranking)."""
    fmu, report, _ = build(beam_spec(), tmp_path, "beam")
    hot = [p for p in report["stress_points"] if "hot spot" in p["description"]]
    assert len(hot) == 4
    named = [p for p in report["stress_points"] if "hot spot" not in p["description"]]
    for p in hot:
        # the case that ranks it: its von Mises stress there is the case's peak over the body
        case = p["description"].split("under ")[1].rstrip(")")
        value = next(c["von_mises"] for c in p["unit_cases"] if c["case"] == case)
        for q in named:
            assert next(c["von_mises"] for c in q["unit_cases"] if c["case"] == case) <= value * (1 + 1e-12)


def test_t_square_steady_spin_vs_calculix_centrif(tmp_path):
    """Paper example 3 spinning steadily at omega = 2 pi (1, 1, 1) rad/s about the axis through
    its mount: the FMU's stresses at its static start under the spin against CalculiX's linear
    static *DLOAD CENTRIF on the same mesh. CalculiX's linear statics leaves out spin softening,
    (omega / omega_1)^2 = 5e-5 of the deformation, which the FMU has: that, not round-off, sets
    the agreement (the flange displacements of test_large_motion agree as closely)."""
    spec = json.loads((EXAMPLES / "t-square.json").read_text())
    spec.pop("$schema")
    spec["outputs"] = {"stress": {"points": [[0.18, 0.0, 0.02], [0.06, 0.02, 0.0], [0.02, 0.05, 0.02]],
                                  "hot_spots": 5}}
    fmu, report, deck = build(spec, tmp_path, "tsquare")
    point = ccx.reference_point(deck, "base")
    analysis = (ccx.rigid_body(deck, "base") + ccx.rigid_body(deck, "left") + ccx.rigid_body(deck, "right")
                + ccx.clamp(deck, "base") + ccx_stress.stress_step(ccx.centrif(ccx.TSQUARE_OMEGA, point, ccx.TSQUARE_AXIS)))
    result = ccx.run_ccx(deck, analysis, tmp_path / "spin")
    nodes = deck_nodes_of(report, deck)
    ours = fmu_static_stresses(fmu, report, {f"base.w[{i + 1}]": 2 * math.pi for i in range(3)})
    exact = ccx_stress.nodal_from_points(deck, ccx_stress.el_print_stresses(result.dat), nodes)
    print("\nT-square steady spin:")
    # measured 4.4e-5 (spin softening, above); the bound, 1e-4, is that of the
    # displacements
    compare("vs CalculiX CENTRIF, integration-point stresses extrapolated exactly",
            ours, np.array([exact[n] for n in nodes]), 1e-4)


def test_beam_stress_history_under_a_sine_load_near_resonance(tmp_path):
    """A sine force at the tip at 95 % of the first frequency: the FMU's stress history at the
    root (Co-Simulation in FMPy, steady state after the transient has decayed) against the full
    FE model's direct frequency response there (the builder's complex solve of the full model,
    report.json accuracy.frequency_response.stress_full), within the reduction's own error
    figure at that frequency (its stress_relative_error)."""
    from fmpy import simulate_fmu

    spec = beam_spec(band=[0.0, 30.0])
    spec["outputs"] = {"stress": {"points": [[0.1, 0.005, 0.01]]}}
    fmu, report, _ = build(spec, tmp_path, "beam")
    fr = report["accuracy"]["frequency_response"]
    f1 = report["accuracy"]["full_hz"][0]
    k = int(np.argmin([abs(f - 0.95 * f1) for f in fr["frequencies_hz"]]))
    f = fr["frequencies_hz"][k]
    assert 0.9 * f1 < f < f1
    # point 0, component sxx, unit load tip f_z (the third of the tip's six)
    nb = 6
    re, im = fr["stress_full"][k][0 * 6 * nb + 0 * nb + 2]
    full = complex(re, im)
    period = 1.0 / f
    dt = period / 1000
    stop = 12.0  # the first mode decays by e in 0.55 s (Rayleigh alpha 1, beta 1e-3): e^-20 left
    signal = np.array([(t, math.sin(2 * math.pi * f * t)) for t in np.arange(0.0, stop + dt, dt)],
                      dtype=[("time", float), ("tip.f[3]", float)])
    result = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=stop, output_interval=dt, input=signal,
                          output=[report["stress_points"][0]["name"] + ".sxx"])
    t = result["time"]
    s = result[result.dtype.names[1]]
    last = t >= stop - 5 * period
    # least-squares fit s = a sin(w t) + b cos(w t): the complex amplitude per unit load is a + i b
    # relative to sin, i.e. H = a + i b for u = Im(e^{iwt})
    w = 2 * math.pi * f
    basis = np.column_stack([np.sin(w * t[last]), np.cos(w * t[last])])
    (a, b), *_ = np.linalg.lstsq(basis, s[last], rcond=None)
    # the FMU holds each step's input over the step (zero-order hold): a delay of dt / 2
    found = complex(a, b) * np.exp(1j * w * dt / 2)
    error = abs(found - full) / abs(full)
    reduction = fr["stress_relative_error"][k]
    print(f"\n  {f:.4f} Hz (f1 {f1:.4f} Hz): root sxx per N, FMU {found:.6e}, full model {full:.6e}: "
          f"deviation {error:.2e}; the reduction's stress error there {reduction:.2e}")
    # measured 1.9e-4 against the reduction's 3.0e-4 (a norm over every point, component and
    # load); the hold's amplitude error (dt w)^2 / 24 = 1.6e-6 and the decayed transient are far
    # below: ten times the reduction's figure
    assert error <= 10 * reduction


@pytest.mark.parametrize("element", ["hex8", "hex20r"])
def test_other_hexahedra_vs_calculix(element, tmp_path):
    """C3D8 and C3D20R (2x2x2 points, trilinear extrapolation to the corners, midsides the
    mean of their edge's corners) on a short bar, tip loads."""
    spec = beam_spec()
    spec["geometry"] = {"element": element,
                        "boxes": [{"min": [0.0, -0.01, -0.01], "max": [0.2, 0.01, 0.01], "elements": [10, 2, 2]}]}
    spec["outputs"] = {"stress": {"points": [[0.05, 0.01, 0.01], [0.1, 0.0, 0.0]], "hot_spots": 4}}
    fmu, report, deck = build(spec, tmp_path, element)
    tip = ccx.cload(deck, "tip", force=(3.0, -2.0, 5.0), moment=(0.3, 0.2, 0.0))
    # measured: 1.6e-6 (C3D8) and 8.4e-7 (C3D20R) against the exact extrapolation (rows' |entries|
    # sum to 5.2 for the trilinear inverse); 5.8e-5 and 2.7e-5 against the .frd (its table to 3
    # decimals: 2.549, -0.683, 0.183, -0.04904)
    check_against_calculix(fmu, report, deck, tmp_path,
                           {"tip.f[1]": 3.0, "tip.f[2]": -2.0, "tip.f[3]": 5.0, "tip.t[1]": 0.3, "tip.t[2]": 0.2},
                           tip, f"bar {element}, tip loads", 2e-5, 6e-4)


def test_documentation_lists_the_points_and_their_unit_case_stresses(tmp_path):
    fmu, report, _ = build(beam_spec(), tmp_path, "beam")
    html = zipfile.ZipFile(fmu).read("documentation/index.html").decode()
    assert "<h2>Stress recovery points</h2>" in html
    assert len(report["stress_points"]) == 7
    for p in report["stress_points"]:
        assert f"<h3>{p['name']}</h3>" in html and p["description"] in html
        # one row per unit load case: six at the tip flange
        assert len(p["unit_cases"]) == 6
        assert all(c["case"] in html for c in p["unit_cases"])


def test_free_floating_body_recovers_stresses(tmp_path):
    """A free body (inertia-relief attachment shapes): hot spots come from the flange's unit
    loads with inertia relief, and under a steady end force the stresses settle on that
    quasi-static state, finite, in Co-Simulation."""
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu
    from test_large_motion import FREE_BLOCK

    spec = json.loads(json.dumps(FREE_BLOCK))
    spec["outputs"] = {"stress": {"hot_spots": 3, "points": [[0.2, 0.0, 0.0]]}}
    path = tmp_path / "free.json"
    path.write_text(json.dumps(spec))
    fmu = tmp_path / "free.fmu"
    run_builder([path, "-o", fmu, "-q"])
    assert validate_fmu(str(fmu)) == []
    report = json.loads(zipfile.ZipFile(fmu).read("documentation/report.json"))
    assert len(report["stress_points"]) == 4
    names = [p["name"] + ".mises" for p in report["stress_points"]]
    result = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=0.5, output_interval=1e-3,
                          start_values={"end.f[1]": 50.0}, output=names)
    mises = np.array([result[n] for n in names])
    assert np.isfinite(mises).all() and mises.max() > 0
