"""Reduction methods, the scene's band and tolerance, and the accuracy report.

References: an independent sparse solve of the full model with SciPy on the matrices the builder
exports (Matrix Market), and the FMU's own transfer functions obtained through FMI calls only
(state-space from finite differences of fmi2GetDerivatives / fmi2GetReal)."""

import json
import zipfile

import numpy as np
import pytest
import scipy.io
import scipy.sparse.linalg

from conftest import EXAMPLES, run_builder
from fmpy.fmi1 import FMICallException
from fmu_access import Fmu
from test_fmi_robustness import Recorder, restore_default_logger  # noqa: F401 (autouse fixture)


def build(tmp_path, spec, name, *extra):
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(spec))
    out = tmp_path / f"{name}.fmu"
    proc = run_builder([path, "-o", out, *extra])
    report = json.loads(zipfile.ZipFile(out).read("documentation/report.json"))
    return out, report, proc.stdout


def lbeam(reduction, scene):
    spec = json.loads((EXAMPLES / "l-beam.json").read_text())
    spec["reduction"] = reduction
    spec["scene"] = scene
    return spec


def extended_matvec(a, x):
    """A x with products and sums in extended precision (x87 long double): the residual of an
    ill-conditioned solve needs more digits than the solve itself."""
    a = a.tocsr()
    data = a.data.astype(np.clongdouble)
    out = np.zeros((a.shape[0], x.shape[1]), dtype=np.clongdouble)
    xl = x.astype(np.clongdouble)
    starts = a.indptr[:-1]
    nonempty = a.indptr[1:] > starts
    for j in range(x.shape[1]):
        prod = data * xl[a.indices, j]
        sums = np.add.reduceat(prod, starts[nonempty])
        out[nonempty, j] = sums
    return out


def scipy_frf(directory, hz, damping):
    """H(w) = B^T (K (1 + i eta) + i w (alpha M + beta K) - w^2 M)^-1 B by SciPy's sparse LU
    (SuperLU), refined on residuals taken in extended precision: the dynamic stiffness at low
    frequency is as ill-conditioned as K (~1e12), which a plain solve pays in digits."""
    k = scipy.io.mmread(directory / "K.mtx").tocsc()  # symmetric: read back mirrored
    m = scipy.io.mmread(directory / "M.mtx").tocsc()
    rows = np.loadtxt(directory / "flange_dofs.txt", dtype=int)
    w = 2 * np.pi * hz
    kc = complex(1.0, damping["loss_factor"] + w * damping["beta"])
    mc = complex(-w * w, w * damping["alpha"])
    z = (k * kc + m * mc).tocsc()
    b = np.zeros((k.shape[0], len(rows)), dtype=complex)
    b[rows, np.arange(len(rows))] = 1.0
    # equilibrate (translations and flange rotations differ by orders of magnitude), factor,
    # refine: x = S (S Z S)^-1 S b
    s = scipy.sparse.diags(1 / np.sqrt(np.abs(k.diagonal())))
    lu = scipy.sparse.linalg.splu((s @ z @ s).tocsc())
    x = s @ lu.solve(s @ b)
    # residuals of the exact-coefficient system kc K + mc M (not of z, whose entries are rounded:
    # at cond ~1e10 that rounding alone moves the answer by 1e-6)
    kl, ml = np.clongdouble(kc), np.clongdouble(mc)
    for _ in range(3):
        r = b.astype(np.clongdouble) - (kl * extended_matvec(k, x) + ml * extended_matvec(m, x))
        x = x + s @ lu.solve(s @ r.astype(complex))
    return x[rows, :]


def test_krylov_and_craig_bampton_meet_the_same_band_tolerance(tmp_path):
    """Paper example 2 with the paper's expansion points s = +-40 pi i, +-280 pi i (20 and 140 Hz):
    Krylov and Craig-Bampton candidates, each cut to the smallest dominant model meeting a 1 %
    flange-FRF tolerance over 0-150 Hz (with the report's 1 % loss factor the floor is ~2e-3:
    near a resonance the FRF error is the frequency error over the damping). Also: the report's
    full-model responses equal an independent SciPy solve on the exported matrices to 1e-8."""
    scene = {"band": [0, 150], "tolerance": 1e-2}
    results = {}
    for name, reduction in [("krylov", {"method": "krylov", "expansion_points": [20, 140], "moments": 3}),
                            ("cb", {"method": "craig_bampton", "modes": 60})]:
        extra = ["--export-matrices", tmp_path / "mm"] if name == "krylov" else []
        path, report, out = build(tmp_path, lbeam(reduction, scene), name, *extra)
        frf = report["accuracy"]["frequency_response"]
        results[name] = (report["order"], frf["max_relative_error"])
        print(f"\n{name}: order {report['order']}, FRF error over 0-150 Hz {frf['max_relative_error']:.2e}")
        assert frf["max_relative_error"] <= 1e-2
        assert frf["band_hz"] == [0, 150]
    frf = json.loads(zipfile.ZipFile(tmp_path / "krylov.fmu").read("documentation/report.json"))["accuracy"]["frequency_response"]
    freqs = frf["frequencies_hz"]
    for i in np.linspace(0, len(freqs) - 1, 6).astype(int):
        ours = np.array([complex(*z) for z in frf["full_matrices"][i]])
        theirs = scipy_frf(tmp_path / "mm", freqs[i], frf["damping"]).ravel()
        err = np.linalg.norm(ours - theirs) / np.linalg.norm(theirs)
        print(f"  full FRF at {freqs[i]:.3f} Hz vs SciPy: {err:.1e}")
        assert err < 1e-8  # measured 1.8e-9 at most (1.25 Hz: the dynamic stiffness is nearly K, cond ~1e12)


SMALL_BEAM = {
    "name": "SmallBeam",
    "geometry": {"element": "hex20", "boxes": [{"min": [0, -0.005, -0.01], "max": [1, 0.005, 0.01], "elements": [20, 1, 1]}]},
    "material": {"E": 2e11, "nu": 0.3, "rho": 7850.0},
    "damping": {"alpha": 1.0, "beta": 0.001},
    "flanges": [
        {"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}},
        {"name": "tip", "role": "force", "nodes": {"box_face": {"box": 0, "face": "+x"}}},
    ],
}


def with_reduction(reduction, scene=None):
    spec = json.loads(json.dumps(SMALL_BEAM))
    spec["reduction"] = reduction
    spec["scene"] = scene or {"band": [0, 600]}
    return spec


@pytest.mark.parametrize("method", ["craig_bampton", "modal", "krylov"])
def test_error_in_band_falls_as_the_order_grows(tmp_path, method):
    """For each method the reported flange-FRF error over the band falls monotonically as the
    order grows (Galerkin projection on nested spaces), until it reaches the round-off floor of
    the comparison (measured 5.5e-10: the full responses are accurate to that at cond(K) ~ 1e10).
    The last order's error, per method: ten times the measured 5.3e-3 (craig_bampton, 10 modes),
    3.2e-4 (modal, 10 modes) and the floor (krylov, 4 moments)."""
    if method == "krylov":
        steps = [{"method": "krylov", "expansion_points": [300], "moments": m} for m in (1, 2, 3, 4)]
    else:
        steps = [{"method": method, "modes": n} for n in (1, 3, 6, 10)]
    errors, orders = [], []
    for i, red in enumerate(steps):
        _, report, _ = build(tmp_path, with_reduction(red), f"{method}{i}")
        errors.append(report["accuracy"]["frequency_response"]["max_relative_error"])
        orders.append(report["order"])
    print(f"\n{method}: orders {orders}, errors " + ", ".join(f"{e:.2e}" for e in errors))
    assert all(b < a or max(a, b) < 5e-9 for a, b in zip(errors, errors[1:]))
    assert errors[-1] < {"craig_bampton": 5e-2, "modal": 3e-3, "krylov": 5e-9}[method]


def fmi_frf(path, freqs_hz):
    """The FMU's tip-to-tip transfer function from FMI calls alone: A by finite differences of
    fmi2GetDerivatives, B from the inputs tip.f/t, C from the outputs tip.u/phi."""
    fmu = Fmu(path, "ModelExchange")
    inputs = [f"tip.f[{i}]" for i in (1, 2, 3)] + [f"tip.t[{i}]" for i in (1, 2, 3)]
    outputs = [f"tip.u[{i}]" for i in (1, 2, 3)] + [f"tip.phi[{i}]" for i in (1, 2, 3)]
    try:
        fmu.initialize()
        x0 = fmu.states()
        a = fmu.jacobian(x0, h=1e-3)
        b = np.zeros((fmu.nx, 6))
        for j, name in enumerate(inputs):
            fmu.set(**{name: 1.0}); dp = fmu.derivatives()
            fmu.set(**{name: 0.0}); d0 = fmu.derivatives()
            b[:, j] = dp - d0
        c = fmu.output_map(x0, outputs)
    finally:
        fmu.close()
    return [c @ np.linalg.solve(2j * np.pi * f * np.eye(fmu.nx) - a, b) for f in freqs_hz]


def test_chosen_order_meets_the_tolerance_when_checked_independently(tmp_path):
    """A tolerance in the scene: the builder picks the smallest dominant model meeting it. Checked
    without the builder: the FMU's transfer function from FMI calls against SciPy's solve of
    the exported full matrices, same Rayleigh damping, over the band."""
    tol = 2e-2
    spec = with_reduction({"method": "craig_bampton", "modes": 12}, {"band": [0, 600], "tolerance": tol})
    # every mode dynamic: this checks the reduction the builder chose, through the state matrix of
    # Model Exchange; at the default cutoff (2 kHz, what a host resolves at a 1 ms output interval,
    # below the band's 6 kHz) the quasi-static modes' dynamics are left out of that matrix (3.3e-2)
    spec["reduction"]["dynamic_cutoff"] = 1e6
    path, report, _ = build(tmp_path, spec, "chosen", "--export-matrices", tmp_path / "mm")
    frf = report["accuracy"]["frequency_response"]
    freqs = frf["frequencies_hz"]
    ours = fmi_frf(path, freqs)
    assert len(ours) == len(freqs) > 0
    scale = 1 / np.sqrt(np.abs(np.diag(report["accuracy"]["compliance_full"])))
    worst = 0.0
    for f, h_fmu in zip(freqs, ours):
        h = scipy_frf(tmp_path / "mm", f, frf["damping"])
        s = np.outer(scale, scale)
        worst = max(worst, np.linalg.norm((h - h_fmu) * s) / np.linalg.norm(h * s))
    print(f"\nchosen order {report['order']} of 18 candidates; independent FRF error {worst:.2e} (tolerance {tol}), "
          f"reported {frf['max_relative_error']:.2e} ({worst / frf['max_relative_error'] - 1:+.1e})")
    assert report["order"] < 18
    assert worst <= tol
    # the same error by two routes (measured 1.5e-13: the central differences' rounding)
    assert worst == pytest.approx(frf["max_relative_error"], rel=2e-12)


def damping_ratios(path):
    """Damping ratio and frequency of every mode from the FMU's state matrix (FMI calls only)."""
    fmu = Fmu(path, "ModelExchange")
    try:
        fmu.initialize()
        a = fmu.jacobian(fmu.states(), h=1e-3)
    finally:
        fmu.close()
    values = np.linalg.eigvals(a)
    values = values[values.imag > 0]
    return sorted((abs(v) / (2 * np.pi), -v.real / abs(v)) for v in values)


def test_modal_damping_one_ratio_and_by_band(tmp_path):
    """Modal damping instead of Rayleigh: every mode of the FMU's state matrix shows the ratio
    asked for (definition of the modal damping ratio: zeta = -Re(s)/|s|; 1e-9)."""
    spec = with_reduction({"method": "craig_bampton", "modes": 6}, {"loads": []})
    spec["damping"] = {"modal_ratio": 0.02}
    path, _, _ = build(tmp_path, spec, "modal_one")
    print(f"\nmodal_ratio: {max(abs(z / 0.02 - 1) for _, z in damping_ratios(path)):.1e}")
    # measured 2.0e-14: the rounding of the central-difference state matrix
    for f, zeta in damping_ratios(path):
        assert zeta == pytest.approx(0.02, rel=2e-13, abs=0), f
    spec["damping"] = {"modal_bands": [{"below": 100, "ratio": 0.01}, {"below": 1000, "ratio": 0.1}]}
    # every mode a state, so the Jacobian shows each mode's own damping (above the default cutoff
    # the modes are quasi-static and carry none)
    spec["reduction"]["dynamic_cutoff"] = 1e9
    path, _, _ = build(tmp_path, spec, "modal_bands")
    seen = set()
    bands = [(f, zeta, 0.01 if f < 100 else 0.1 if f < 1000 else 0.0) for f, zeta in damping_ratios(path)]
    print("modal_bands: worst " + f"{max(abs(z - e) / max(e, 0.01) for _, z, e in bands):.1e} of the ratio")
    for f, zeta, expected in bands:
        # modal damping of undamped frequency f_n: |s| = f_n exactly; as above, 2e-13
        assert zeta == pytest.approx(expected, rel=2e-13, abs=2e-15), f
        seen.add(expected)
    assert seen == {0.01, 0.1, 0.0}


def test_a_scene_without_rotation_has_no_rotation_terms(tmp_path):
    """Model only what the scene needs: without rotation in the scene the FMU carries no
    rotating-frame invariants (smaller resource, cheaper step: see `fmu-builder --sweep`), and a
    rotating mount is refused with a message instead of being simulated wrongly."""
    plain, _, _ = build(tmp_path, with_reduction({"method": "craig_bampton", "modes": 6}, {"loads": []}), "plain")
    rotating, _, _ = build(tmp_path, with_reduction({"method": "craig_bampton", "modes": 6}, {"loads": ["rotation"]}), "rot")
    size = lambda p: zipfile.ZipFile(p).getinfo("resources/reduced_body.bin").file_size
    assert size(plain) < size(rotating)
    rec = Recorder()
    fmu = Fmu(plain, "CoSimulation", callbacks=rec.callbacks)
    try:
        fmu.set(**{"base.w[3]": 1.0})
        with pytest.raises(FMICallException):
            fmu.initialize()
    finally:
        fmu.close(terminate=False)
    assert "built for a scene without rotation" in rec.text(), rec.text()


def test_sweep_prints_error_cost_and_build_time(tmp_path):
    """`fmu-builder --sweep`: every method at growing orders, error in band, cost per step and
    build time side by side, and an SVG plot of error against cost (timings are printed, not
    asserted: speed belongs to benchmarks)."""
    path = tmp_path / "sweep.json"
    path.write_text(json.dumps(with_reduction({"method": "krylov", "expansion_points": [300], "moments": 2})))
    svg = tmp_path / "sweep.svg"
    proc = run_builder([path, "--sweep", "--sweep-svg", svg])
    print("\n" + proc.stdout)
    rows = [line.split("|")[1:-1] for line in proc.stdout.splitlines() if line.startswith("| ") and "method" not in line]
    methods = {r[0].strip() for r in rows}
    assert {"craig_bampton", "modal", "krylov"} <= methods
    krylov = [float(r[3]) for r in rows if r[0].strip() == "krylov"]
    assert krylov[-1] < krylov[0]
    assert any("rotation declared" in r[1] and r[5].strip() != "-" for r in rows)
    import xml.etree.ElementTree as ET
    root = ET.parse(svg).getroot()
    assert root.tag.endswith("svg")
    # every run a marker labelled with its order
    text = svg.read_text()
    assert text.count("<circle") >= len(rows) - sum("declared" in r[1] for r in rows)
    orders = {f"r={int(r[2])}" for r in rows if "declared" not in r[1]}
    assert all(o in text for o in orders), orders


def test_only_connected_flanges_are_modelled(tmp_path):
    """A flange the scene does not connect is left out: no variables, no static shapes, and its
    surface stays free (a rigid tie there would stiffen the part)."""
    spec = json.loads((EXAMPLES / "t-square.json").read_text())
    spec["scene"]["connected"] = ["left"]
    path, report, _ = build(tmp_path, spec, "left_only")
    from fmpy import read_model_description
    names = {v.name for v in read_model_description(str(path)).modelVariables}
    assert "left.u[1]" in names and not any(n.startswith("right.") for n in names)
    assert [f["name"] for f in report["flanges"]] == ["base", "left"]
    full = json.loads(zipfile.ZipFile(run_builder([EXAMPLES / "t-square.json", "-o", tmp_path / "all.fmu"]) and tmp_path / "all.fmu").read("documentation/report.json"))
    assert report["order"] < full["order"]


def test_krylov_at_a_real_expansion_point(tmp_path):
    """Moment matching at a real point s = sigma (K + sigma^2 M, definite): static flange loads
    stay exact (the s = 0 block is always in) and the band converges with the moments."""
    errors = []
    for moments in (1, 3):
        red = {"method": "krylov", "real_expansion_points": [1000.0], "moments": moments}
        _, report, _ = build(tmp_path, with_reduction(red), f"real{moments}")
        print(f"\ncompliance {report['accuracy']['compliance_max_relative_error']:.1e}")
        assert report["accuracy"]["compliance_max_relative_error"] < 1e-11  # measured 6.4e-13
        errors.append(report["accuracy"]["frequency_response"]["max_relative_error"])
    print(f"\nreal point 1000 1/s: FRF error {errors[0]:.2e} (1 moment) -> {errors[1]:.2e} (3 moments)")
    # measured 6.2e-2 -> 1.3e-10: three moments reach the comparison's floor
    assert errors[1] < 1.5e-9 and errors[0] > 1e3 * errors[1]
