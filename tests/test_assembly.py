"""Assemblies: several bodies and joints solved inside one FMU (examples/assemblies), run as a
user runs them: FMPy's simulate_fmu with start values only, libcosim and Ecos at h = 1 ms.

References nobody here computed: the one-piece model of the welded links (its FMU, itself
checked against CalculiX in test_chain.py) and CalculiX on its mesh; rigid-body theory
(Lagrange's equations, tests/rigid_mechanisms.py and test_chain.rigid_double_pendulum); Exudyn's
floating-frame bodies on CalculiX's matrices of the same link mesh (tests/exudyn_reference.py).

Run with -s to see the measured figures."""

import json
import sys
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

import calculix as ccx
from conftest import EXAMPLES, ROOT, run_builder

sys.path.insert(0, str(ROOT / "examples" / "chain"))
ASSEMBLIES = EXAMPLES / "assemblies"
H = 1e-3
NO_GRAVITY = {"g[3]": 0.0}


def build(name, d, source=None):
    fmu = d / f"{name}.fmu"
    run_builder([source or ASSEMBLIES / f"{name}.json", "-o", fmu, "-q", "--force"])
    return fmu


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("assemblies")
    names = ["two_link_weld", "double_pendulum", "three_link_chain", "four_bar", "slider_crank"]
    fmus = {n: build(n, d) for n in names}
    one_piece, deck = d / "OnePiece.fmu", d / "one_piece.inp"
    run_builder([EXAMPLES / "chain" / "one_piece.json", "-o", one_piece, "--export-inp", deck, "-q"])
    return fmus, one_piece, deck.read_text(), d


@pytest.fixture(scope="module")
def link_matrices(built):
    """The link's CalculiX deck, a work folder and CalculiX's matrices of it (for Exudyn)."""
    from exudyn_reference import ccx_matrices

    d = built[3]
    deck = d / "link.inp"
    run_builder([EXAMPLES / "chain" / "link.json", "-o", d / "LinkForDeck.fmu", "--export-inp", deck, "-q"])
    workdir = d / "exudyn"
    return deck.read_text(), workdir, ccx_matrices(deck.read_text(), workdir)


def simulate(fmu, stop, outputs, start=None, step=H):
    """FMPy's simulate_fmu in Co-Simulation with start values only, an output every step; rows
    from t = 0."""
    res = simulate_fmu(str(fmu), stop_time=stop, step_size=step, output_interval=step, fmi_type="CoSimulation",
                       start_values=start or {}, output=outputs)
    return res["time"], np.column_stack([res[c] for c in outputs])


def test_every_example_validates(built):
    """FMPy's validation has nothing to say about any assembly FMU's modelDescription.xml, and
    it declares Co-Simulation only."""
    from fmpy import read_model_description

    for name, fmu in built[0].items():
        assert validate_fmu(str(fmu)) == [], name
        md = read_model_description(str(fmu))
        assert md.coSimulation is not None and md.modelExchange is None, name


# ---------------------------------------------------------------------------------------------
# two links welded: the one-piece beam


TIP_LOAD = {"tip.f[2]": -0.5, "tip.f[3]": -1.0}
WELD_OUT = ["upper.tip.r[2]", "upper.tip.r[3]", "lower.tip.r[2]", "lower.tip.r[3]"]
ONE_PIECE_OUT = ["joint.r[2]", "joint.r[3]", "tip.r[2]", "tip.r[3]"]


def mean_period(t, x):
    x = x - 0.5 * (x.max() + x.min())
    up = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    crossings = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    assert len(crossings) >= 4, "fewer than three periods"
    return (crossings[-1] - crossings[0]) / (len(crossings) - 1)


def test_weld_tip_load_vs_one_piece_and_calculix(built):
    """A tip load (0, -0.5, -1) N on the lower link from t = 0, no gravity, 2 s at h = 1 ms:
    the weld's and the tip's lateral and vertical motion against the one-piece FMU (same start
    values, FMPy), as a fraction of each one's swing, and the two lowest frequencies from the
    tip's periods against CalculiX's frequencies of the one-piece mesh (clamped base, rigid
    weld section and tip)."""
    fmus, one_piece, deck, d = built
    t, ours = simulate(fmus["two_link_weld"], 2.0, WELD_OUT, {**NO_GRAVITY, **TIP_LOAD})
    _, theirs = simulate(one_piece, 2.0, ONE_PIECE_OUT, {**NO_GRAVITY, **TIP_LOAD})
    dev = np.abs(ours - theirs).max(axis=0) / np.ptp(theirs, axis=0)
    analysis = (ccx.rigid_body(deck, "base") + ccx.rigid_body(deck, "joint") + ccx.rigid_body(deck, "tip")
                + ccx.clamp(deck, "base") + ccx.frequency_step(4))
    f_ccx = np.array(ccx.run_ccx(deck, analysis, d / "ccx_freq").frequencies_hz[:2])
    f_ours = np.array([1 / mean_period(t, ours[:, c]) for c in (2, 3)])
    rel_f = np.abs(f_ours / f_ccx - 1)
    print(f"\nweld, tip load: weld y, z and tip y, z within {dev} of the one piece's swing; frequencies "
          f"{f_ours} Hz vs CalculiX {f_ccx} ({rel_f})")
    assert dev.max() <= 1e-3
    assert np.all(rel_f <= 2e-3)


def test_weld_gravity_from_rest_vs_one_piece(built):
    """Both links at rest under gravity from t = 0 (the scene where a master with a one-step delay
    diverges within 0.033 s), 1 s at h = 1 ms, against the one-piece FMU."""
    fmus, one_piece, _, _ = built
    _, ours = simulate(fmus["two_link_weld"], 1.0, WELD_OUT)
    _, theirs = simulate(one_piece, 1.0, ONE_PIECE_OUT)
    swing = np.ptp(theirs[:, 3])
    dev = np.abs(ours - theirs).max() / swing
    print(f"\nweld, gravity from rest: tip swing {swing:.4g} m, assembly - one piece {dev:.2e} of it")
    assert dev <= 1e-2


# ---------------------------------------------------------------------------------------------
# mechanisms against rigid-body theory and Exudyn


def test_double_pendulum_vs_rigid_theory_and_exudyn(built, link_matrices):
    """examples/assemblies/double_pendulum.json, 12 s (five periods of the slow mode) at
    h = 1 ms: elbow and tip (x, z) against the rigid double pendulum of two uniform bars
    (Lagrange's equations, test_chain.rigid_double_pendulum) and against Exudyn's flexible double
    pendulum of the same mesh (CalculiX's matrices, Exudyn's own Craig-Bampton modes, joints and
    generalised-alpha at h = 1 ms), as fractions of the rigid pendulum's swing."""
    from exudyn_reference import double_pendulum as exudyn_double_pendulum
    from test_chain import rigid_double_pendulum

    t, ours = simulate(built[0]["double_pendulum"], 12.0,
                       ["upper.tip.r[1]", "upper.tip.r[3]", "lower.tip.r[1]", "lower.tip.r[3]"])
    theirs = rigid_double_pendulum([np.pi / 4, np.pi / 4], t, length=1.0)
    swing = np.ptp(theirs, axis=0)
    rigid = np.abs(ours - theirs).max(axis=0) / swing
    deck, workdir, matrices = link_matrices
    t_ex, exudyn = exudyn_double_pendulum(deck, workdir, seconds=12.0, matrices=matrices)
    assert exudyn.shape == ours.shape and np.allclose(t_ex, t)
    against_exudyn = np.abs(ours - exudyn).max(axis=0) / swing
    early = np.abs(ours[:2001] - exudyn[:2001]).max() / swing.max()
    print(f"\ndouble pendulum, 12 s: within {rigid} of the rigid pendulum's swing ({swing} m), within "
          f"{against_exudyn} of Exudyn's ({early:.1e} over the first 2 s)")
    assert rigid.max() <= 1e-2
    assert against_exudyn.max() <= 1e-2


def test_three_link_chain_vs_rigid_theory_and_exudyn(built, link_matrices):
    """examples/assemblies/three_link_chain.json, 4 s at h = 1 ms: each link's tip (x, z)
    against three uniform rigid bars (rigid_mechanisms.rigid_pendulum_chain) and against
    Exudyn's chain of three flexible links of the same mesh."""
    import rigid_mechanisms as rm
    from exudyn_reference import pendulum_chain

    names = [f"link{i}.tip.r[{c}]" for i in (1, 2, 3) for c in (1, 3)]
    t, ours = simulate(built[0]["three_link_chain"], 4.0, names)
    theirs = rm.rigid_pendulum_chain(3, [np.pi / 4] * 3, t)
    swing = np.ptp(theirs, axis=0)
    rigid = np.abs(ours - theirs).max(axis=0) / swing
    deck, workdir, matrices = link_matrices
    _, exudyn = pendulum_chain(deck, workdir, n_links=3, seconds=4.0, matrices=matrices)
    against_exudyn = np.abs(ours - exudyn).max(axis=0) / swing
    print(f"\nthree-link chain, 4 s: within {rigid.max():.2e} of the rigid chain's swing, {against_exudyn.max():.2e} "
          f"of Exudyn's")
    assert rigid.max() <= 1e-2
    assert against_exudyn.max() <= 1e-2


def test_four_bar_vs_rigid_theory_and_exudyn(built, link_matrices):
    """examples/assemblies/four_bar.json, 6 s at h = 1 ms (the crank's spin-up and five turns):
    the rocker's angle, the coupler's far end C (x, z) and the torque the ground applies to the
    crank (about +y), against the rigid four-bar (rigid_mechanisms.rigid_four_bar) and Exudyn's
    four-bar with the same flexible coupler and rigid crank and rocker. The torque is compared
    from t = 0.1 s: a coupler started straight rings in its joints for the first 50 ms."""
    import rigid_mechanisms as rm
    from exudyn_reference import four_bar

    t, ours = simulate(built[0]["four_bar"], 6.0,
                       ["rocker_pivot.angle", "coupler.tip.r[1]", "coupler.tip.r[3]", "drive.t[3]"])
    theirs = rm.rigid_four_bar(t)
    swing = np.ptp(theirs, axis=0)
    late = t >= 0.1
    rigid = np.abs(ours - theirs).max(axis=0) / swing
    rigid[3] = np.abs(ours[late, 3] - theirs[late, 3]).max() / swing[3]
    deck, workdir, matrices = link_matrices
    _, exudyn = four_bar(deck, workdir, seconds=6.0, matrices=matrices)
    against = np.abs(ours - exudyn[:, :4]).max(axis=0) / swing
    against[3] = np.abs(ours[late, 3] - exudyn[late, 3]).max() / swing[3]
    print(f"\nfour-bar, 6 s: rocker angle, C x, C z, crank torque within {rigid} of the rigid four-bar's swing "
          f"({swing}), within {against} of Exudyn's")
    assert rigid[:3].max() <= 1e-3 and rigid[3] <= 2e-2
    assert against.max() <= 1e-2


def test_slider_crank_vs_rigid_theory(built):
    """examples/assemblies/slider_crank.json, 6 s at h = 1 ms: the slider's position and its
    normal load on the rod against the rigid rod's kinematics and moment balance
    (test_chain.rigid_slider_crank). The rod starts straight, not sagging: its ringing decays
    (stiffness-proportional damping) over the first seconds, so the load is compared from
    t = 2 s, the position over the whole run."""
    import slider_crank as sc
    from test_chain import rigid_slider_crank

    t, ours = simulate(built[0]["slider_crank"], 6.0, ["slide.position", "slide.f[2]"])
    crank = sc.Crank(0.2, 2 * np.pi, 1.0)
    x_ref, _ = rigid_slider_crank(crank, t, 1.0)
    _, load_ref = rigid_slider_crank(crank, t, 1.0)
    x = 1.2 + ours[:, 0]
    x_error = np.abs(x - x_ref).max() / np.ptp(x_ref)
    late = t >= 2.0
    load_error = np.abs(ours[late, 1] - load_ref[late]).max() / np.ptp(load_ref)
    print(f"\nslider-crank, 6 s: slider x within {x_error:.2e} of its swing ({np.ptp(x_ref):.3g} m), its load from "
          f"2 s within {load_error:.2e} of its swing ({np.ptp(load_ref):.3g} N)")
    assert x_error <= 1e-4
    assert load_error <= 2e-2
