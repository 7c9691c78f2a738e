"""The references of the assembly scenes checked against each other: the rigid-body theory of
tests/rigid_mechanisms.py (scipy only) and the flexible multibody models of
tests/exudyn_reference.py (CalculiX's matrices of the link, Exudyn's floating-frame bodies,
joints and integrator). Nothing of the builder or the FMUs is used: the link's CalculiX deck is
written here with tests/meshes.py, the mesh of examples/chain/link.json (hex20 50 x 2 x 2 on
[0, 1] x [-0.005, 0.005] x [-0.01, 0.01], steel E = 2e11, nu = 0.3, rho = 7850, node sets BASE on
x = 0 and TIP on x = 1).

Run with -s to see the measured deviations; the Exudyn comparisons are marked slow (tens of
seconds each): pytest -m slow tests/test_references.py."""

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

import rigid_mechanisms as rm
from meshes import BoxMesh
from test_chain import rigid_double_pendulum

H = 1e-3


def link_deck() -> str:
    """The link's CalculiX deck (examples/chain/link.json's mesh and material), without the
    builder: C3D20 elements in set SOLID, node sets BASE (x = 0) and TIP (x = 1)."""
    mesh = BoxMesh("C3D20", (1.0, 0.01, 0.02), (50, 2, 2))
    mesh.coords = [x - np.array([0.0, 0.005, 0.01]) for x in mesh.coords]
    base = mesh.nodes_where(lambda x: abs(x[0]) < 1e-12)
    tip = mesh.nodes_where(lambda x: abs(x[0] - 1.0) < 1e-12)
    return mesh.deck({"BASE": base, "TIP": tip}, material=(2.0e11, 0.3, 7850.0))


@pytest.fixture(scope="module")
def link_matrices(tmp_path_factory):
    """The link's deck, a work folder, and CalculiX's mass and stiffness matrices of it (as
    test_chain.py's fixture of the same name, from tests/meshes.py's deck instead of the
    builder's export)."""
    from exudyn_reference import ccx_matrices

    deck = link_deck()
    workdir = tmp_path_factory.mktemp("references")
    matrices = ccx_matrices(deck, workdir)
    mass = matrices[2].sum() / 3  # rigid translation: the total mass, three times
    assert mass == pytest.approx(7850.0 * 1.0 * 0.01 * 0.02, rel=1e-12)
    return deck, workdir, matrices


# ------------------------------------------------------------------------------------------------
# rigid theory against itself


def test_rigid_chain_of_two_is_the_double_pendulum():
    """rigid_pendulum_chain(2) (the general-n mass matrix and Coriolis terms) against
    test_chain.rigid_double_pendulum (the two-link equations written out), 12 s from
    (0.7, 1.1) rad. Measured 0 (the same operations; 3e-15 m from (0.7, 0.7)); tolerance 1e-9."""
    t = np.arange(12001) * H
    ours = rm.rigid_pendulum_chain(2, [0.7, 1.1], t)
    theirs = rigid_double_pendulum([0.7, 1.1], t)
    assert ours.shape == theirs.shape == (len(t), 4)
    print(f"\nrigid chain of two vs the double pendulum: {np.abs(ours - theirs).max():.1e} m")
    assert np.abs(ours - theirs).max() <= 1e-9


def test_rigid_chain_keeps_its_energy_and_its_lengths():
    """The three-link chain from rest (45 deg below the horizontal, in line), 6 s: each link's
    ends stay 1 m apart (to 1e-12) and the energy (from the rates by central differences of the
    sampled positions, so to the differences' O(h^2)) stays within 1e-4 of m g L (one bar's
    weight times its length): measured 7.8e-6, the differences' error."""

    t = np.arange(6001) * H
    p = rm.rigid_pendulum_chain(3, [np.pi / 4] * 3, t).reshape(len(t), 3, 2)
    ends = np.concatenate([np.zeros((len(t), 1, 2)), p], axis=1)
    lengths = np.linalg.norm(np.diff(ends, axis=1), axis=2)
    assert np.abs(lengths - 1.0).max() <= 1e-12
    m, inertia = rm.bar(1.0)
    centres = 0.5 * (ends[:, 1:] + ends[:, :-1])
    v = np.gradient(centres, t, axis=0, edge_order=2)
    d = np.diff(ends, axis=1)
    w = np.gradient(np.unwrap(np.arctan2(d[..., 0], -d[..., 1]), axis=0), t, axis=0, edge_order=2)
    energy = (0.5 * m * np.sum(v ** 2, axis=2) + 0.5 * inertia * w ** 2 + m * 9.81 * centres[..., 1]).sum(axis=1)
    drift = np.abs(energy - energy[0]).max() / (m * 9.81)
    print(f"\nrigid chain of three, 6 s: lengths within {np.abs(lengths - 1).max():.1e} m, energy within "
          f"{drift:.1e} m g L (finite differences)")
    assert drift <= 1e-4


def test_rigid_four_bar_closes_and_balances():
    """The driven four-bar, 6 s (the spin-up and five turns): |C - D| = 0.75 and |C - B| = 1.0
    to 1e-12; the start C(0) = (0.916667, 0, 0.745356); the crank's torque by Lagrange's
    equation in phi and by the bars' Newton-Euler equations with the joint forces (measured
    4e-15 N m apart: tolerance 1e-12 of the swing); the work of that torque (Simpson on the 1 ms
    samples) against the change of kinetic plus potential energy (measured 7e-9 J of an 8.6 J
    range: tolerance 1e-8 of the range)."""
    t = np.arange(6001) * H
    rows = rm.rigid_four_bar(t)
    assert rows.shape == (len(t), 4)
    phi, rate, _ = rm.crank_motion(t)
    k = rm.four_bar_kinematics(phi)
    closure = max(np.abs(np.linalg.norm(k["C"] - [1.0, 0.0], axis=1) - 0.75).max(),
                  np.abs(np.linalg.norm(k["C"] - k["B"], axis=1) - 1.0).max())
    assert closure <= 1e-12
    assert np.allclose(rows[0], [0.0, 11 / 12, np.sqrt(0.5625 - 1 / 144), rows[0, 3]], rtol=0, atol=1e-15)
    assert np.allclose(k["C"], rows[:, 1:3], rtol=0, atol=0)
    tau_ne, _ = rm.four_bar_torque_newton_euler(t)
    swing = np.ptp(rows[:, 3])
    torque_gap = np.abs(tau_ne - rows[:, 3]).max()
    energy = rm.four_bar_energy(t)
    work = cumulative_simpson(rows[:, 3] * rate, x=t, initial=0.0)
    balance = np.abs(work - (energy - energy[0])).max()
    print(f"\nrigid four-bar, 6 s: closure {closure:.1e} m; torque swing {swing:.4g} N m, Lagrange vs Newton-Euler "
          f"{torque_gap:.1e} N m; work vs energy {balance:.1e} J of {np.ptp(energy):.4g} J; rocker swing "
          f"{np.ptp(rows[:, 0]):.4g} rad")
    assert torque_gap <= 1e-12 * swing
    assert balance <= 1e-8 * np.ptp(energy)


def test_rigid_four_bar_rates_are_the_positions_derivatives():
    """The closed-form velocities and accelerations (bars' centres and angles) against central
    differences of the positions and velocities at 1 ms: the difference's O(h^2) error, measured
    at most 1.6e-5 m/s and 1.3e-3 m/s^2 and rad/s^2 (the crank's jerk jumps at the end of the
    spin-up); tolerances 1e-4 and 1e-2."""
    t = np.arange(6001) * H
    s = rm.four_bar_state(t)
    for b in s["bodies"]:
        assert np.abs(np.gradient(b["centre"], t, axis=0) - b["velocity"])[1:-1].max() <= 1e-4
        assert np.abs(np.gradient(b["velocity"], t, axis=0) - b["acceleration"])[1:-1].max() <= 1e-2
        assert np.abs(np.gradient(np.unwrap(b["angle"]), t) - b["omega"])[1:-1].max() <= 1e-4
        assert np.abs(np.gradient(b["omega"], t) - b["alpha"])[1:-1].max() <= 1e-2


# ------------------------------------------------------------------------------------------------
# Exudyn's flexible models against the rigid theory


@pytest.mark.slow
def test_exudyn_four_bar_vs_rigid_theory(link_matrices):
    """Exudyn's four-bar with the flexible 1 m coupler (exudyn_reference.four_bar, h = 1 ms,
    6 s: the spin-up and five turns, ~11 s to run) against rigid_four_bar.

    Measured: the rocker's angle within 1.9e-6 of its swing (0.73 rad), C's x and z within
    2.1e-6 and 1.5e-6 of theirs (the coupler's axial strain), the same at h = 0.5 ms. The
    torque on the crank from t = 0.1 s within 1.3e-3 of its swing (10.4 N m; 8.6e-4 at
    h = 0.5 ms: a multiplier of an index-3 constraint, alternating from step to step); before
    that, the start from an undeformed coupler at rest rings (0.14 of the swing in the first
    10 ms, 1.9e-2 up to 50 ms, 1.7e-4 from 50 to 200 ms). The coupler's mid-span deflection
    from t = 0.1 s against rigid_mechanisms.four_bar_coupler_deflection (a pinned beam, quasi-
    static under its weight and the d'Alembert loads of the rigid motion): within 1.0e-2 of its
    swing (1.9e-4 m; the bending modes' dynamic part), the means 1.7e-3 apart. Tolerances: 2e-5
    of the swing for the angle and C, 1.3e-2 for the torque, 0.1 of the swing and 2e-2 of the
    mean for the deflection: ten times the measured."""
    from exudyn_reference import four_bar

    deck, workdir, matrices = link_matrices
    t, ours = four_bar(deck, workdir / "four_bar", seconds=6.0, matrices=matrices)
    assert ours.shape == (6001, 5) and np.allclose(t, np.arange(6001) * H)
    theirs = rm.rigid_four_bar(t)
    swing = np.ptp(theirs, axis=0)
    kinematics = np.abs(ours[:, :3] - theirs[:, :3]).max(axis=0) / swing[:3]
    late = t >= 0.1
    torque = np.abs(ours[late, 3] - theirs[late, 3]).max() / swing[3]
    start = np.abs(ours[~late, 3] - theirs[~late, 3]).max() / swing[3]
    beam = rm.four_bar_coupler_deflection(t)
    sag = np.abs(ours[late, 4] - beam[late]).max() / np.ptp(beam[late])
    mean = ours[late, 4].mean() / beam[late].mean() - 1
    print(f"\nExudyn's flexible four-bar vs the rigid one, 6 s: rocker angle, C x, C z within {kinematics} of the "
          f"swing ({swing[:3]}); the crank's torque within {torque:.2e} of its swing ({swing[3]:.4g} N m) from "
          f"0.1 s ({start:.2e} before); mid-span deflection within {sag:.2e} of the quasi-static beam's swing "
          f"({np.ptp(beam[late]):.3e} m), means {mean:+.1e} apart")
    assert kinematics.max() <= 2e-5
    assert torque <= 1.3e-2
    assert sag <= 0.1 and abs(mean) <= 2e-2


@pytest.mark.slow
def test_exudyn_pendulum_chain_vs_rigid_theory(link_matrices):
    """Exudyn's chain of three flexible 1 m links (exudyn_reference.pendulum_chain, from rest
    in line at 45 deg below the horizontal, h = 1 ms, 4 s, ~17 s to run) against
    rigid_pendulum_chain(3). Measured: the links' ends within 9.8e-4 of their swing (1.5e-4
    over the first second: the links bend under the joint forces and the motion is chaotic, so
    late differences grow); tolerance 1e-2, ten times."""
    from exudyn_reference import pendulum_chain

    deck, workdir, matrices = link_matrices
    t, ours = pendulum_chain(deck, workdir / "chain", n_links=3, seconds=4.0, matrices=matrices)
    assert ours.shape == (4001, 6) and np.allclose(t, np.arange(4001) * H)
    theirs = rm.rigid_pendulum_chain(3, [np.pi / 2 - np.radians(45.0)] * 3, t)
    swing = np.ptp(theirs, axis=0)
    error = np.abs(ours - theirs).max(axis=0) / swing
    first = np.abs(ours[t <= 1.0] - theirs[t <= 1.0]).max(axis=0) / swing
    print(f"\nExudyn's chain of three flexible links vs the rigid chain, 4 s: the ends (x, z) within {error} of "
          f"their swing ({swing} m); {first.max():.1e} over the first second")
    assert error.max() <= 1e-2
