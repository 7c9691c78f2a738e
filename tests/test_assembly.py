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
