"""Two bodies connected: examples/chain, two links (1 m steel beams) welded tip flange to mount
and co-simulated by the iterating master examples/chain/chain_master.py, against the one-piece
model of the same 2 m beam (examples/chain/one_piece.json: one mesh, the same elements per
metre, a rigid section at the weld as the links' flanges have).

References nobody here computed: CalculiX on the one-piece model's exported mesh (frequencies,
static sag under gravity), and through it the one-piece FMU. The chain is compared with both:
static sag, the transient after a tip load over eight periods of the second mode (its
deflection and its two lowest frequencies), the transient under gravity from rest (the scene
in which a delayed master diverges), and its own convergence in the step.

Run with -s to see the measured deviations."""

import json
import sys
import zipfile

import numpy as np
import pytest

import calculix as ccx
from conftest import EXAMPLES, ROOT, run_builder

sys.path.insert(0, str(ROOT / "examples" / "chain"))
import chain_master as cm  # noqa: E402

G = {"g[3]": -9.81}
H = 1e-3
TIP = [f"tip.r[{i}]" for i in (1, 2, 3)]
JOINT = [f"joint.r[{i}]" for i in (1, 2, 3)]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("chain")
    link, one_piece, deck = d / "Link.fmu", d / "OnePiece.fmu", d / "one_piece.inp"
    run_builder([EXAMPLES / "chain" / "link.json", "-o", link, "-q"])
    run_builder([EXAMPLES / "chain" / "one_piece.json", "-o", one_piece, "--export-inp", deck, "-q"])
    return link, one_piece, deck.read_text(), d


@pytest.fixture(scope="module")
def link_matrices(fmus):
    """The link's exported CalculiX deck, a work folder, and CalculiX's mass and stiffness
    matrices of it (for the Exudyn references)."""
    from exudyn_reference import ccx_matrices

    d = fmus[3]
    deck = d / "link.inp"
    run_builder([EXAMPLES / "chain" / "link.json", "-o", d / "LinkForDeck.fmu", "--export-inp", deck, "-q"])
    workdir = d / "exudyn"
    return deck.read_text(), workdir, ccx_matrices(deck.read_text(), workdir)


def chain_of(link, start=None, step=H, static=False):
    bodies = [cm.Body(str(link), f"link{i}", {**G, **(start or {})}) for i in range(2)]
    chain = cm.Chain.welded(bodies, ["tip"], ["base"], step)
    chain.initialize(static=static)
    return chain


def run_chain(chain, seconds, load=None):
    """Joint and tip positions after every step; `load` on the lower link's tip from t = 0."""
    upper, lower = chain.bodies
    if load:
        lower.set([lower.vr[k] for k in load], list(load.values()))
    joint_refs, tip_refs = upper.refs("tip", ["r[1]", "r[2]", "r[3]"]), lower.refs("tip", ["r[1]", "r[2]", "r[3]"])
    out = []
    for _ in range(int(round(seconds / chain.h))):
        chain.step()
        out.append(np.concatenate([upper.get(joint_refs), lower.get(tip_refs)]))
    return np.array(out)


def run_one_piece(path, seconds, step=H, static=False, load=None, start=None):
    body = cm.Body(str(path), "one_piece", {**G, **(start or {})})
    body.instantiate({"static_start": True} if static else {})
    if load:
        body.set([body.vr[k] for k in load], list(load.values()))
    refs = [body.vr[k] for k in JOINT + TIP]
    out = []
    for k in range(int(round(seconds / step))):
        body.fmu.doStep(k * step, step)
        out.append(body.get(refs))
    return np.array(out)


def mean_period(t, x):
    """The mean period between the first and last upward crossings of x's mean (linear
    interpolation between samples)."""
    x = x - 0.5 * (x.max() + x.min())
    up = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    crossings = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    assert len(crossings) >= 4, "fewer than three periods"
    return (crossings[-1] - crossings[0]) / (len(crossings) - 1)


def test_one_piece_frequencies_vs_calculix(fmus):
    """The reference's own reference: the one-piece model's first six frequencies (base
    clamped, weld section and tip rigid and free), the builder's full FE model and the reduced
    model in the FMU, vs CalculiX *FREQUENCY on the same mesh. Tolerances: the full model 1e-6
    (CalculiX prints 7 digits) plus 2e-5 (f_1 / f_k)^2 for the lowest modes, ten times the 2.2e-6
    measured at f_1 (2.04 Hz, bending about the thin side: the round-off of a slender model's
    softest mode, as test_calculix's L-beam); the reduced model 3e-4, ten times its largest
    measured reduction error (3.2e-5 at mode 6, 70 Hz)."""
    _, one_piece, deck, d = fmus
    report = json.loads(zipfile.ZipFile(one_piece).read("documentation/report.json"))
    analysis = (ccx.rigid_body(deck, "base") + ccx.rigid_body(deck, "joint") + ccx.rigid_body(deck, "tip")
                + ccx.clamp(deck, "base") + ccx.frequency_step(10))
    theirs = np.array(ccx.run_ccx(deck, analysis, d / "ccx_freq").frequencies_hz[:6])
    full = np.array(report["accuracy"]["full_hz"][:6])
    reduced = np.array(report["accuracy"]["reduced_hz"][:6])
    assert len(theirs) == len(full) == len(reduced) == 6
    print("\none piece: CalculiX, full model, reduced model [Hz]")
    for a, b, c in zip(theirs, full, reduced):
        print(f"  {a:12.7g} {b:12.7f} ({b / a - 1:.1e}) {c:12.7f} ({c / a - 1:.1e})")
    assert np.all(np.abs(full / theirs - 1) <= 1e-6 + 2e-5 * (theirs[0] / theirs) ** 2)
    assert np.all(np.abs(reduced / theirs - 1) <= 3e-4)


def test_static_sag_vs_calculix_and_one_piece(fmus):
    """The chain started in static equilibrium under gravity (each link's static_start, the
    lower link's weight on the upper by fixed point) vs CalculiX's static solution of the
    one-piece mesh under *DLOAD GRAV and vs the one-piece FMU's static start: the weld's and
    the tip's deflection. Measured: 6.6e-5 and 4.4e-5 of the deflection against CalculiX, the
    chain's large-rotation kinematics against CalculiX's linear statics (the lower link turns
    with the weld by 0.02 rad, cos - 1 = 2e-4 of its lever); tolerance 1e-3."""
    link, one_piece, deck, d = fmus
    chain = chain_of(link, static=True)
    upper, lower = chain.bodies
    ours = np.concatenate([upper.get(upper.refs("tip", ["r[3]"])), lower.get(lower.refs("tip", ["r[3]"]))])
    op = cm.Body(str(one_piece), "one_piece", G)
    op.instantiate({"static_start": True})
    theirs_fmu = op.get([op.vr["joint.r[3]"], op.vr["tip.r[3]"]])
    analysis = (ccx.rigid_body(deck, "base") + ccx.rigid_body(deck, "joint") + ccx.rigid_body(deck, "tip")
                + ccx.clamp(deck, "base")
                + ccx.static_step(ccx.gravity(9.81, (0, 0, -1)), prints=["JOINT_REF", "TIP_REF"]))
    result = ccx.run_ccx(deck, analysis, d / "ccx_sag")
    theirs = np.array([result.u(ccx.set_node(deck, "JOINT_REF"))[2], result.u(ccx.set_node(deck, "TIP_REF"))[2]])
    rel_ccx = np.abs(ours - theirs) / np.abs(theirs)
    rel_fmu = np.abs(ours - theirs_fmu) / np.abs(theirs_fmu)
    print(f"\nstatic sag [m]: chain {ours}, one-piece FMU {theirs_fmu}, CalculiX {theirs}")
    print(f"  chain vs CalculiX {rel_ccx}, vs one-piece FMU {rel_fmu}")
    assert np.all(rel_ccx <= 7e-4) and np.all(rel_fmu <= 7e-4)


def test_tip_load_transient_vs_one_piece(fmus):
    """A tip load (0, -0.5, -1) N on the lower link from t = 0, both links at rest, no gravity
    (the scene where the one-piece linear model is the exact reference: no prestress, small
    rotations), 2 s at h = 1 ms (4 periods of the first mode, y, 2.04 Hz; 8 of the second, z,
    4.08 Hz): the weld's and the tip's lateral and vertical motion against the one-piece FMU,
    as a fraction of each one's swing, and the two lowest frequencies from the tip's periods.
    Measured: 2.2e-4 (y) and 8.5e-4 (z) of the swing, the step's coupling error (it shrinks
    with h, test_chain_converges_in_the_step); frequencies 7.9e-6 and 1.8e-5 apart.
    Tolerances ten times: 9e-3 and 2e-4."""
    link, one_piece, _, _ = fmus
    load = {"tip.f[2]": -0.5, "tip.f[3]": -1.0}
    no_gravity = {"g[3]": 0.0}
    ours = run_chain(chain_of(link, start=no_gravity), 2.0, load)
    theirs = run_one_piece(one_piece, 2.0, load=load, start=no_gravity)
    assert ours.shape == theirs.shape == (2000, 6)
    t = H * np.arange(1, 2001)
    worst = 0.0
    for col, name in [(1, "weld y"), (2, "weld z"), (4, "tip y"), (5, "tip z")]:
        swing = np.ptp(theirs[:, col])
        dev = np.abs(ours[:, col] - theirs[:, col]).max() / swing
        worst = max(worst, dev)
        print(f"\n  {name}: swing {swing:.4g} m, chain - one piece {dev:.2e} of the swing", end="")
    f_ours = np.array([1 / mean_period(t, ours[:, c]) for c in (4, 5)])
    f_theirs = np.array([1 / mean_period(t, theirs[:, c]) for c in (4, 5)])
    rel_f = np.abs(f_ours / f_theirs - 1)
    print(f"\n  frequencies from the tip's periods: chain {f_ours} Hz, one piece {f_theirs} Hz ({rel_f})")
    assert worst <= 9e-3
    assert np.all(rel_f <= 2e-4)


def test_gravity_from_rest_vs_one_piece(fmus):
    """The scene where a delayed master diverges: both links at rest under gravity from t = 0,
    1 s at h = 1 ms. Against the one-piece FMU, as a fraction of the tip's swing. Measured:
    1.0e-3; the same run at g / 10 gives 4.2e-4, the step's coupling error, and the rest is the
    chain's large-rotation kinematics against the one-piece model's linear ones (it grows with
    the swing). Tolerance 1e-2, ten times."""
    link, one_piece, _, _ = fmus
    ours = run_chain(chain_of(link), 1.0)
    theirs = run_one_piece(one_piece, 1.0)
    swing = np.ptp(theirs[:, 5])
    dev = np.abs(ours[:, [2, 5]] - theirs[:, [2, 5]]).max() / swing
    print(f"\ngravity from rest: tip swing {swing:.4g} m, chain - one piece {dev:.2e} of the swing")
    assert dev <= 1e-2


def test_chain_converges_in_the_step(fmus):
    """The same scene at h = 1 ms and at h = 0.125 ms, 0.5 s: the step's coupling error.
    Measured 2.5e-4 of the tip's swing; tolerance 2.5e-3, ten times."""
    link, _, _, _ = fmus
    coarse = run_chain(chain_of(link), 0.5)
    fine = run_chain(chain_of(link, step=H / 8), 0.5)[7::8]
    assert coarse.shape == fine.shape
    swing = np.ptp(fine[:, 5])
    dev = np.abs(coarse - fine).max() / swing
    print(f"\nh = 1 ms vs h = 0.125 ms: {dev:.2e} of the tip's swing")
    assert dev <= 2.5e-3


def test_a_delayed_master_diverges(fmus):
    """Why the chain master iterates: the same two links connected by a plain Jacobi loop
    (outputs read after each step, set as the other's inputs before the next, held over the
    step, as libcosim and Ecos do) blow up within 0.1 s at h = 1 ms. The docs' claim, kept
    true."""
    link, _, _, _ = fmus
    upper, lower = (cm.Body(str(link), f"link{i}", G) for i in range(2))
    upper.instantiate()
    lower.instantiate({f"base.{n}": v for n, v in zip(cm.MOTION, upper.get(upper.refs("tip", cm.MOTION)))})
    tip_motion, tip_load = upper.refs("tip", cm.MOTION), upper.refs("tip", cm.WRENCH)
    mount_motion, reaction = lower.refs("base", cm.MOTION), lower.refs("base", cm.WRENCH)
    lower_tip = lower.vr["tip.r[3]"]
    blown_up_at = None
    for k in range(100):
        motion, force = upper.get(tip_motion), -lower.get(reaction)
        lower.set(mount_motion, motion)
        upper.set(tip_load, force)
        try:
            upper.fmu.doStep(k * H, H)
            lower.fmu.doStep(k * H, H)
        except Exception:
            blown_up_at = k * H
            break
        if abs(lower.get([lower_tip])[0]) > 10.0:
            blown_up_at = (k + 1) * H
            break
    print(f"\nJacobi at h = 1 ms: the lower tip beyond 10 m (or a step refused) at t = {blown_up_at} s")
    assert blown_up_at is not None and blown_up_at <= 0.1


def test_long_run_decays_as_the_one_piece_model(fmus):
    """100 periods of the z mode (24.5 s at h = 1 ms) after a tip load of -1 N along z, no
    gravity, light damping (damping.beta = 1e-4: 0.13 % at 4.08 Hz, so that the one-piece
    model's amplitude falls to 0.45 over the run): the chain's amplitude per period never
    grows and it ends no larger than the one-piece model's. Measured: the chain's last period
    0.413 of its second, the one-piece model's 0.452: the coupling dissipates a little (1.4e-4 of
    critical), it never feeds energy in. Tolerances: no period above the one before by more
    than 1e-3 of the swing (a period's peak sampled at 1 ms); the chain's final ratio at most the
    one-piece model's (plus that 1e-3) and at least 0.8 of it, twice the dissipation measured.
    An undamped chain is not covered: it diverges in this master (docs/CONNECTING.md)."""
    link, one_piece, _, _ = fmus
    start = {"g[3]": 0.0, "damping.beta": 1e-4}
    load = {"tip.f[3]": -1.0}
    seconds = 100 / 4.0779
    ours = run_chain(chain_of(link, start=start), seconds, load)[:, 5]
    theirs = run_one_piece(one_piece, seconds, load=load, start=start)[:, 5]
    assert ours.shape == theirs.shape
    period = int(round(1 / 4.0779 / H))
    amp_ours = np.array([np.ptp(ours[k:k + period]) for k in range(0, len(ours) - period + 1, period)])
    amp_theirs = np.array([np.ptp(theirs[k:k + period]) for k in range(0, len(theirs) - period + 1, period)])
    assert len(amp_ours) == len(amp_theirs) == 100
    growth = np.diff(amp_ours[1:]).max() / amp_ours[1]
    ratio = (amp_ours[-1] / amp_ours[1]) / (amp_theirs[-1] / amp_theirs[1])
    print(f"\n100 periods: chain {amp_ours[-1] / amp_ours[1]:.3f}, one piece {amp_theirs[-1] / amp_theirs[1]:.3f} "
          f"of the second period's amplitude; largest growth between periods {growth:.1e}")
    assert growth <= 1e-3
    assert 0.8 <= ratio <= 1.0 + 1e-3


def rigid_double_pendulum(phi0, t, length=1.0, width=0.01, height=0.02, rho=7850.0, g=9.81):
    """Two uniform rigid bars (length x width x height, swinging in the plane of `length` and
    `height`) hung end to end from a fixed pivot, by Lagrange's equations in the absolute angles
    from the downward vertical, from rest at `phi0`: the elbow and the tip (x, z) at times `t`."""
    from scipy.integrate import solve_ivp
    m, c = rho * length * width * height, length / 2
    inertia = m * (length ** 2 + height ** 2) / 12  # about the centre of mass, across the plane

    def rates(_, y):
        p1, p2, w1, w2 = y
        d = p1 - p2
        mass = np.array([[inertia + m * c * c + m * length ** 2, m * length * c * np.cos(d)],
                         [m * length * c * np.cos(d), inertia + m * c * c]])
        force = np.array([-m * length * c * np.sin(d) * w2 ** 2 - (m * c + m * length) * g * np.sin(p1),
                          m * length * c * np.sin(d) * w1 ** 2 - m * c * g * np.sin(p2)])
        return [w1, w2, *np.linalg.solve(mass, force)]

    sol = solve_ivp(rates, (0.0, t[-1]), [phi0[0], phi0[1], 0.0, 0.0], t_eval=t, method="DOP853",
                    rtol=1e-11, atol=1e-12)
    assert sol.success
    p1, p2 = sol.y[0], sol.y[1]
    return np.column_stack([length * np.sin(p1), -length * np.cos(p1),
                            length * (np.sin(p1) + np.sin(p2)), -length * (np.cos(p1) + np.cos(p2))])


def double_pendulum(link, seconds, pivot_degrees=45.0):
    """Two links hung from a pivot on the ground and from each other by revolute joints about y
    (chain_master's --pivot y:45 --joint y), released from rest, straight at `pivot_degrees`
    below the horizontal, under gravity, h = 1 ms: elbow and tip (x, z) from t = 0, and the
    retaken steps per step."""
    bodies = [cm.Body(str(link), f"link{i}", G) for i in range(2)]
    pivot = np.radians(pivot_degrees)
    joints = [cm.Joint(None, 0, "base", axis=[0, 1, 0], angle=pivot),
              cm.Joint(0, 1, "base", "tip", axis=[0, 1, 0])]
    chain = cm.Chain(bodies, joints, H)
    chain.initialize()
    elbow, tip = bodies[0].refs("tip", ["r[1]", "r[3]"]), bodies[1].refs("tip", ["r[1]", "r[3]"])
    ours = [np.concatenate([bodies[0].get(elbow), bodies[1].get(tip)])]
    for _ in range(int(round(seconds / H))):
        chain.step()
        ours.append(np.concatenate([bodies[0].get(elbow), bodies[1].get(tip)]))
    return np.array(ours), chain.evaluations / (len(ours) - 1)


def double_pendulum_vs_rigid(ours, length, pivot_degrees=45.0):
    """Deviation from the rigid double pendulum, per column, as a fraction of its swing; the
    swing."""
    t = np.arange(len(ours)) * H
    # the mount's x axis turned by the pivot angle about y points pi/2 - angle from the vertical
    theirs = rigid_double_pendulum([np.pi / 2 - np.radians(pivot_degrees)] * 2, t, length=length)
    assert ours.shape == theirs.shape
    swing = np.ptp(theirs, axis=0)
    return np.abs(ours - theirs).max(axis=0) / swing, swing


def test_double_pendulum_vs_rigid_theory_and_exudyn(fmus, link_matrices):
    """A flexible double pendulum of the 1 m links, 12 s (five periods of its slow mode, 2.4 s).
    References: the rigid double pendulum of two uniform bars of the links' size and mass
    (Lagrange's equations, integrated to 1e-11); and Exudyn's flexible double pendulum of the
    same mesh (tests/exudyn_reference.py: CalculiX's mass and stiffness matrices, Exudyn's own
    Craig-Bampton modes, floating-frame bodies, joints and integrator, h = 1 ms). The links bend
    by about 1e-3 m under the joint forces (first bending mode 16 Hz, the pendulum's 0.4 and
    1.1 Hz). Measured, as fractions of the swing: against the rigid pendulum 8.0e-4 (Exudyn's
    own 1.8e-3, a step half as long moving it by 4e-5), against Exudyn 9.7e-4 (1.8e-4 over the
    first 2 s; the motion is chaotic, so late differences grow). Tolerances 8e-3 and 1e-2, ten
    times (the issue asks for 1e-2)."""
    from exudyn_reference import double_pendulum as exudyn_double_pendulum

    link = fmus[0]
    ours, retakes = double_pendulum(link, 12.0)
    rigid_error, swing = double_pendulum_vs_rigid(ours, 1.0)
    deck, workdir, matrices = link_matrices
    t, exudyn = exudyn_double_pendulum(deck, workdir, seconds=12.0, matrices=matrices)
    assert exudyn.shape == ours.shape and np.allclose(t, np.arange(len(ours)) * H)
    exudyn_error = np.abs(ours - exudyn).max(axis=0) / swing
    print(f"\ndouble pendulum of 1 m links, 12 s: elbow x, z and tip x, z within {rigid_error} of the rigid "
          f"pendulum's swing ({swing} m), within {exudyn_error} of Exudyn's; {retakes:.2f} retaken steps per step")
    assert rigid_error.max() <= 8e-3
    assert exudyn_error.max() <= 1e-2


def test_double_pendulum_of_stiff_links_vs_rigid_theory(fmus):
    """The same with examples/chain/short_link.json (0.25 m, first bending mode 260 Hz, most
    modes above the step's Nyquist frequency and relaxing), 6 s (five periods, 1.2 s). A first
    version of the revolute joint, with the mean of the axial torque at both ends of the step
    as its equation, rang at the step's Nyquist frequency and diverged here within 6 s (and
    within 2 s with the 1 m links' modulus raised fifty-fold). Measured: 2.3e-4 of the swing;
    tolerance 2.3e-3, ten times that."""
    d = fmus[3]
    short = d / "ShortLink.fmu"
    run_builder([EXAMPLES / "chain" / "short_link.json", "-o", short, "-q"])
    ours, retakes = double_pendulum(short, 6.0)
    error, swing = double_pendulum_vs_rigid(ours, 0.25)
    print(f"\ndouble pendulum of 0.25 m links, 6 s: elbow x, z and tip x, z within {error} of the swing ({swing} m); "
          f"{retakes:.2f} retaken steps per step")
    assert error.max() <= 2.3e-3


def rigid_slider_crank(crank, t, length, height=0.02, width=0.01, rho=7850.0, g=9.81):
    """A rigid connecting rod (a uniform bar, length x width x height, moving in the plane of
    `length` and `height`) between the crank pin and a frictionless, massless slider on the x
    axis, under gravity -z: the slider's position from the kinematics and its normal load on
    the rod from the rod's moment balance about the moving pin,
    L N cos(psi) = (L/2) m g cos(psi) - J_pin psi'' + m (L/2)(sin(psi) a_x + cos(psi) a_z),
    psi the rod's angle (its axis (cos psi, 0, -sin psi)), a the pin's acceleration."""
    phi, rate, acceleration = crank.angle(t)
    r = crank.radius
    s = -(r / length) * np.sin(phi)
    c = np.sqrt(1.0 - s * s)
    x = r * np.cos(phi) + length * c
    psi_rate = -(r / length) * np.cos(phi) * rate / c
    psi_acceleration = ((r / length) * (np.sin(phi) * rate ** 2 - np.cos(phi) * acceleration) + psi_rate ** 2 * s) / c
    m = rho * length * width * height
    inertia_pin = m * (length ** 2 + height ** 2) / 12 + m * length ** 2 / 4
    ax = -acceleration * r * np.sin(phi) - rate ** 2 * r * np.cos(phi)
    az = -acceleration * r * np.cos(phi) + rate ** 2 * r * np.sin(phi)
    load = ((length / 2) * m * g * c - inertia_pin * psi_acceleration
            + m * (length / 2) * (s * ax + c * az)) / (length * c)
    return x, load


def test_slider_crank_vs_rigid_theory_and_exudyn(fmus, link_matrices):
    """A slider-crank (examples/chain/slider_crank.py): crank radius 0.2 m spun up from rest
    over 1 s to 1 rev/s, the 1 m link as a flexible connecting rod on a revolute joint at the
    crank pin, its tip on a slider along x; static start (the rod sagging between pin and
    slider), h = 1 ms, 6 s (the spin-up and five revolutions). References: the rigid rod's
    kinematics and moment balance; and Exudyn's flexible slider-crank of the same mesh
    (tests/exudyn_reference.py: CalculiX's matrices, Exudyn's Craig-Bampton body, the rod's
    base forced onto the crank pin's path by a joint turning freely about y, its tip held on
    the x axis, static start, generalised-alpha at h = 1 ms).

    Measured against the rigid rod: the slider's position within 8.5e-7 of its swing (0.4 m:
    the rod's axial compliance), the slider's normal load (a step's mean, against the reference
    at the step's midpoint) within 1.2e-3 of its swing (4.5 N; 1.2e-3 at h = 0.5 ms too: the
    rod's bending, not the step; Exudyn's own load is 1.2e-3 off the rigid rod too); the static
    start's load 7.7008 N against m g / 2 = 7.7009 N. Against Exudyn: the slider's position
    within 3.0e-10 of the swing, its load within 2.3e-4 (Exudyn's load at the step's
    midpoint, the mean of its values at both ends). Tolerances: position 1e-5 against the
    rigid rod (its axial compliance left out), 3e-9 against Exudyn; load 1e-2 against the
    rigid rod (the issue's figure, eight times the measured), 2.3e-3 against Exudyn; static
    load 1e-4 relative: about ten times each measured figure."""
    import slider_crank as sc
    from exudyn_reference import slider_crank as exudyn_slider_crank
    crank = sc.Crank(0.2, 2 * np.pi, 1.0)
    chain, rod, slider = sc.slider_crank(str(fmus[0]), crank)
    m = 7850.0 * 1.0 * 0.01 * 0.02
    assert slider.load[2] == pytest.approx(m * 9.81 / 2, rel=1e-4)
    rows, chain = sc.run(str(fmus[0]), crank, 6.0)
    t = rows[:, 0]
    x_ref, _ = rigid_slider_crank(crank, t, 1.0)
    _, load_ref = rigid_slider_crank(crank, t - H / 2, 1.0)
    assert len(rows) == len(x_ref) == len(load_ref) == 6000
    x_error = np.abs(rows[:, 1] - x_ref).max() / np.ptp(x_ref)
    load_error = np.abs(rows[:, 3] - load_ref).max() / np.ptp(load_ref)
    print(f"\nslider-crank, 6 s: slider x within {x_error:.2e} of its swing ({np.ptp(x_ref):.3g} m), the rod's "
          f"tip off the line by {np.abs(rows[:, 2]).max():.2e} m, the slider's load within {load_error:.2e} of its "
          f"swing ({np.ptp(load_ref):.3g} N); {chain.evaluations / len(rows):.2f} retaken steps per step")
    assert x_error <= 1e-5
    assert load_error <= 1e-2

    deck, workdir, matrices = link_matrices
    t_exudyn, exudyn = exudyn_slider_crank(deck, workdir, lambda time: crank.pin(time)[:3], seconds=6.0,
                                           matrices=matrices)
    assert len(t_exudyn) == len(exudyn) == len(rows) + 1 and np.allclose(t_exudyn[1:], t)
    x_exudyn = np.abs(rows[:, 1] - exudyn[1:, 0]).max() / np.ptp(x_ref)
    load_exudyn = np.abs(rows[:, 3] - 0.5 * (exudyn[1:, 2] + exudyn[:-1, 2])).max() / np.ptp(load_ref)
    print(f"  against Exudyn's flexible slider-crank: slider x within {x_exudyn:.2e} of the swing, the load within "
          f"{load_exudyn:.2e}")
    assert x_exudyn <= 3e-9
    assert load_exudyn <= 2.3e-3


def test_the_master_refuses_what_it_cannot_carry():
    """Joints out of order, a body on two joints, a slider without a direction, a revolute
    joint without an axis, a ground joint naming a flange: refused with the reason, before any
    FMU is touched (the bodies here are placeholders)."""
    bodies = [object(), object()]
    with pytest.raises(ValueError, match="upper body must come before it"):
        cm.Chain(bodies, [cm.Joint(1, 0, "base", "tip")], H)
    with pytest.raises(ValueError, match="one joint at most"):
        cm.Chain(bodies, [cm.Joint(None, 1, "base"), cm.Joint(0, 1, "base", "tip")], H)
    with pytest.raises(ValueError, match="the step must be positive"):
        cm.Chain(bodies, [cm.Joint(0, 1, "base", "tip")], 0.0)
    with pytest.raises(ValueError, match="non-zero direction"):
        cm.Slider(0, "tip", [0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="slider on body 2: there are 2 bodies"):
        cm.Chain(bodies, [], H, sliders=[cm.Slider(2, "tip", [0, 0, 0], [1, 0, 0])])
    with pytest.raises(ValueError, match="the axis must be a non-zero 3-vector"):
        cm.Joint(None, 0, "base", axis=[0, 0, 0])
    with pytest.raises(ValueError, match="the ground has none"):
        cm.Joint(None, 0, "base", "tip")


def test_chain_is_bounded_at_any_step(fmus):
    """The welded links under gravity from rest, 2 s, at communication steps of 2 to 50 ms
    (the links' FMU built for 1 ms): never further from rest than the one-piece model gets
    (no energy fed in at a coarse step), the error against it growing with the step. Measured:
    the largest tip deflection 0.9996, 0.998, 0.984, 0.946 and 0.59 of the one-piece model's
    at 2, 5, 10, 20 and 50 ms; the error 3.4e-3, 2.0e-2, 0.10, 0.18 and 0.52 of the swing (1.4e-3
    at 1 ms, against the one-piece model sampled at the chain's steps). Tolerances: the largest
    deflection at most 1.001 of the one-piece model's (round-off of a sampled peak); at 2 ms
    the error at most 3.4e-2, ten times."""
    link, one_piece, _, _ = fmus
    reference = run_one_piece(one_piece, 2.0)[:, 5]
    peak = np.abs(reference).max()
    print()
    for h in (2e-3, 5e-3, 1e-2, 2e-2, 5e-2):
        ours = run_chain(chain_of(link, step=h), 2.0)[:, 5]
        k = int(round(h / H))
        sampled = reference[k - 1::k]
        assert len(ours) == len(sampled) == int(round(2.0 / h))
        error = np.abs(ours - sampled).max() / np.ptp(reference)
        print(f"h = {h * 1e3:g} ms: largest tip deflection {np.abs(ours).max() / peak:.5f} of the one-piece "
              f"model's, error {error:.2e} of the swing")
        assert np.abs(ours).max() <= 1.001 * peak
        if h == 2e-3:
            assert error <= 3.4e-2


def model_exchange_chain(link, seconds, rtol):
    """The two links welded as a Modelica tool imports them: both FMUs in Model Exchange, one
    ODE of both bodies' states integrated by SciPy's BDF (atol = rtol x the states' nominals),
    the joint's loop solved in every right-hand side through the feedthroughs (the upper tip's
    motion, a and z included, drives the lower mount; the load W on the upper tip makes
    W + the lower mount's reaction zero), by a fixed number of Newton iterations with a
    Jacobian of the loop taken once, so that the right-hand side is a smooth function of the
    state, as a stiff integrator's difference Jacobian needs. Returns the lower tip's z at every
    millisecond after t = 0."""
    import ctypes
    from scipy.integrate import solve_ivp
    from fmu_access import Fmu

    upper, lower = Fmu(str(link)), Fmu(str(link))
    try:
        for body in (upper, lower):
            body.set(**G)
        upper.initialize()
        tip_motion = [upper.vr[f"tip.{n}"] for n in cm.MOTION]
        tip_load = [upper.vr[f"tip.{n}"] for n in cm.WRENCH]
        mount_motion = [lower.vr[f"base.{n}"] for n in cm.MOTION]
        reaction = [lower.vr[f"base.{n}"] for n in cm.WRENCH]
        lower.fmu.setReal(mount_motion, upper.fmu.getReal(tip_motion))
        lower.initialize()
        n = upper.nx

        def loop(w):
            upper.fmu.setReal(tip_load, list(w))
            lower.fmu.setReal(mount_motion, upper.fmu.getReal(tip_motion))
            return w + np.array(lower.fmu.getReal(reaction))

        jacobian = None

        def rhs(t, x):
            nonlocal jacobian
            for body in (upper, lower):
                body.fmu.setTime(t)
            upper.set_states(x[:n])
            lower.set_states(x[n:])
            if jacobian is None:
                r0 = loop(np.zeros(6))
                jacobian = np.column_stack([loop(e) - r0 for e in np.eye(6)])
            w = np.zeros(6)
            for _ in range(6):
                w = w - np.linalg.solve(jacobian, loop(w))
            residual = loop(w)
            assert np.abs(residual).max() <= 1e-7 * max(1.0, np.abs(w).max()), residual
            return np.concatenate([upper.derivatives(), lower.derivatives()])

        nominals = np.zeros(2 * n)
        for k, body in enumerate((upper, lower)):
            part = np.zeros(n)
            body.fmu.getNominalsOfContinuousStates(part.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n)
            nominals[k * n:(k + 1) * n] = part
        grid = np.arange(1, int(round(seconds / H)) + 1) * H
        x0 = np.concatenate([upper.states(), lower.states()])
        sol = solve_ivp(rhs, (0.0, seconds), x0, method="BDF", rtol=rtol, atol=rtol * nominals, t_eval=grid)
        assert sol.success, sol.message
        tip = []
        for k, t in enumerate(sol.t):
            rhs(t, sol.y[:, k])
            tip.append(lower.get("tip.r[3]")[0])
        return np.array(tip)
    finally:
        upper.close()
        lower.close()


def test_model_exchange_chain_in_a_generic_host(fmus):
    """The links welded in Model Exchange, the loop solved in every right-hand side (what a
    Modelica tool does with two imported FMUs connected through MultiBody frames), under
    gravity from rest for 1 s, against the one-piece FMU, as a fraction of the tip's swing.
    With every mode dynamic in Model Exchange (`reduction.dynamic_cutoff` above the highest
    mode): 7.4e-4 at rtol 1e-6 and 8.7e-4 at 1e-4 (fmusim's and many tools' default);
    tolerance 8e-3, ten times. With the links' default split (their two highest modes
    quasi-static in Model Exchange) the chain is 8.9e-2 off, and with the modes above 200 Hz
    quasi-static 0.26: Model Exchange's flange accelerations leave out the quasi-static modes'
    acceleration, and those modes carry the tip's static flexibility, which a body hung from it
    follows (docs/CONNECTING.md); checked here too, as more than 3e-2, so that the documented
    limit stays true."""
    link, one_piece, _, d = fmus
    spec = json.loads((EXAMPLES / "chain" / "link.json").read_text())
    spec["name"] = "LinkAllDynamic"
    spec["reduction"]["dynamic_cutoff"] = 1e5
    all_dynamic = d / "link_all_dynamic.json"
    all_dynamic.write_text(json.dumps(spec))
    all_dynamic_fmu = d / "LinkAllDynamic.fmu"
    run_builder([all_dynamic, "-o", all_dynamic_fmu, "-q"])
    reference = run_one_piece(one_piece, 1.0)[:, 5]
    swing = np.ptp(reference)
    print()
    for path, rtol, bound in ((all_dynamic_fmu, 1e-6, 8e-3), (all_dynamic_fmu, 1e-4, 8e-3), (link, 1e-6, None)):
        ours = model_exchange_chain(path, 1.0, rtol)
        assert ours.shape == reference.shape
        error = np.abs(ours - reference).max() / swing
        print(f"Model Exchange chain, {path.name}, rtol {rtol:g}: {error:.2e} of the tip's swing")
        if bound is None:
            assert error > 3e-2
        else:
            assert error <= bound
