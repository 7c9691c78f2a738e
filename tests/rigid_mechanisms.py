"""Rigid-body theory for the multibody scenes of the assembly tests: closed-form equations of
uniform rigid bars, integrated or evaluated with numpy and scipy only (no Exudyn, nothing of the
builder). The flexible references of the same scenes are in tests/exudyn_reference.py.

    p = rigid_pendulum_chain(3, [phi1, phi2, phi3], t)
    # (len(t), 6): the ends of links 1, 2, 3 (x, z) every sample of t
    rows = rigid_four_bar(t)
    # (len(t), 4): rocker angle, C's x and z, the driving torque on the crank

Plane and signs (both scenes): the mechanisms move in the world x-z plane, every joint turns
about world y, gravity is -z. An angle theta "about +y" turns the world x axis into
e(theta) = (cos theta, 0, -sin theta) (the right-hand rule about +y), and a body turning at
theta' has the angular velocity theta' y. A moment about y of a force F at the arm r is
(r x F)_y = r_z F_x - r_x F_z.

The bars are uniform boxes `length` x `width` (y, out of the plane) x `height` (in the plane),
mass m = rho length width height and moment of inertia about the centre for rotation about y
m (length^2 + height^2) / 12."""

from __future__ import annotations

import numpy as np

#: the four-bar's geometry [m]: ground pivots O and D, crank O-B, coupler B-C, rocker D-C
FOUR_BAR = {"O": (0.0, 0.0), "D": (1.0, 0.0), "crank": 0.25, "coupler": 1.0, "rocker": 0.75}


def bar(length, width=0.01, height=0.02, rho=7850.0):
    """(mass, moment of inertia about the centre for rotation across the plane) of a uniform bar."""
    m = rho * length * width * height
    return m, m * (length ** 2 + height ** 2) / 12.0


# ------------------------------------------------------------------------------------------------
# n bars hung end to end


def chain_mass_matrix(phi, length, mass, inertia):
    """The chain's mass matrix in the absolute angles `phi` (n,), and the coefficients mu (n, n)
    with M_ij = mu_ij cos(phi_i - phi_j) for i != j. Bar k's centre is
    sum_{j<k} L e_j + c e_k with e_j = (sin phi_j, -cos phi_j), c = L/2, so
    M_ii = I + m c^2 + m L^2 (n - 1 - i) and mu_ij = m L (c + L (n - 1 - max(i, j)))."""
    n = len(phi)
    c = length / 2
    k = np.arange(n)
    mu = mass * length * (c + length * (n - 1 - np.maximum.outer(k, k)))
    d = np.subtract.outer(phi, phi)
    M = mu * np.cos(d)
    M[k, k] = inertia + mass * c * c + mass * length ** 2 * (n - 1 - k)
    return M, mu


def rigid_pendulum_chain(n, phi0, t, length=1.0, width=0.01, height=0.02, rho=7850.0, g=9.81):
    """n uniform rigid bars (length x width x height, swinging in the plane of `length` and
    `height`) hung end to end from a fixed pivot at the origin, every joint a revolute about
    world y, gravity -z; phi_k is bar k's absolute angle from the downward vertical (its axis
    (sin phi_k, 0, -cos phi_k), positive turning from -z towards +x, i.e. about -y). Released
    from rest at `phi0` (n angles) at t[0] = 0. Lagrange's equations for general n,

        sum_j mu_ij [cos(phi_i - phi_j) phi_j'' + sin(phi_i - phi_j) phi_j'^2]
            + m g (c + L (n - 1 - i)) sin phi_i = 0,   mu_ii := I + m c^2 + m L^2 (n - 1 - i),

    (chain_mass_matrix; the Coriolis and centrifugal terms in closed form), integrated by DOP853 at
    rtol 1e-11, atol 1e-12 and sampled at `t`. Returns (len(t), 2 n): the end of bar k (x, z) in
    world coordinates for k = 1..n (the joints, then the tip)."""
    from scipy.integrate import solve_ivp

    phi0 = np.asarray(phi0, dtype=float)
    if phi0.shape != (n,):
        raise ValueError(f"phi0 needs {n} angles")
    m, inertia = bar(length, width, height, rho)
    c = length / 2
    gravity = m * g * (c + length * (n - 1 - np.arange(n)))

    def rates(_, y):
        p, w = y[:n], y[n:]
        M, mu = chain_mass_matrix(p, length, m, inertia)
        s = mu * np.sin(np.subtract.outer(p, p))  # zero diagonal
        force = -s @ (w * w) - gravity * np.sin(p)
        return np.concatenate([w, np.linalg.solve(M, force)])

    t = np.asarray(t, dtype=float)
    sol = solve_ivp(rates, (0.0, t[-1]), np.concatenate([phi0, np.zeros(n)]), t_eval=t, method="DOP853",
                    rtol=1e-11, atol=1e-12)
    if not sol.success:
        raise RuntimeError(sol.message)
    p = sol.y[:n].T
    x, z = length * np.cumsum(np.sin(p), axis=1), -length * np.cumsum(np.cos(p), axis=1)
    return np.stack([x, z], axis=2).reshape(len(t), 2 * n)


# ------------------------------------------------------------------------------------------------
# The four-bar


def crank_motion(t, crank_speed=2 * np.pi, spin_up=1.0):
    """The crank's prescribed angle about +y, its rate and its acceleration at `t`: the rate
    crank_speed (1 - cos(pi t / spin_up)) / 2 until spin_up, then crank_speed; the angle its
    integral from phi(0) = 0."""
    t = np.asarray(t, dtype=float)
    w, T = crank_speed, spin_up
    early = t < T
    te = np.minimum(t, T)
    phi = np.where(early, 0.5 * w * (te - T / np.pi * np.sin(np.pi * te / T)), 0.5 * w * T + w * (t - T))
    rate = np.where(early, 0.5 * w * (1 - np.cos(np.pi * te / T)), w)
    acceleration = np.where(early, 0.5 * w * np.pi / T * np.sin(np.pi * te / T), 0.0)
    return phi, rate, acceleration


def _e(theta):
    """e(theta) = (cos theta, -sin theta) in (x, z) and its derivative, as (n, 2) arrays."""
    return (np.stack([np.cos(theta), -np.sin(theta)], axis=-1),
            np.stack([-np.sin(theta), -np.cos(theta)], axis=-1))


def four_bar_kinematics(phi, geometry=FOUR_BAR):
    """Closed-form position analysis and velocity and acceleration coefficients of the four-bar
    at the crank angles `phi` (about +y; a 1-D array): B = O + r1 e(phi), C the intersection of
    the circles |C - B| = r2 and |C - D| = r3 on the left of B -> D in (x, z) (z > 0 at
    phi = 0), the coupler's angle beta and the rocker's angle gamma about +y (C = B + r2 e(beta)
    = D + r3 e(gamma)), k_beta = d beta / d phi, k_gamma = d gamma / d phi and their derivatives
    in phi (the loop equation r1 e(phi) + r2 e(beta) - r3 e(gamma) = D - O differentiated once
    and twice). Returns a dict of arrays, points as (n, 2) in (x, z)."""
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    O, D = np.array(geometry["O"]), np.array(geometry["D"])
    r1, r2, r3 = geometry["crank"], geometry["coupler"], geometry["rocker"]
    e1, de1 = _e(phi)
    B = O + r1 * e1
    BD = D - B
    d = np.linalg.norm(BD, axis=-1)
    u = BD / d[:, None]
    n = np.stack([-u[:, 1], u[:, 0]], axis=-1)
    a = (r2 ** 2 - r3 ** 2 + d ** 2) / (2 * d)
    h = np.sqrt(r2 ** 2 - a ** 2)
    C = B + a[:, None] * u + h[:, None] * n
    beta = np.arctan2(-(C - B)[:, 1], (C - B)[:, 0])
    gamma = np.arctan2(-(C - D)[:, 1], (C - D)[:, 0])
    e2, de2 = _e(beta)
    e3, de3 = _e(gamma)
    # r2 de2 k_beta - r3 de3 k_gamma = -r1 de1: a 2 x 2 solve per sample (Cramer's rule)
    a11, a21, a12, a22 = r2 * de2[:, 0], r2 * de2[:, 1], -r3 * de3[:, 0], -r3 * de3[:, 1]
    det = a11 * a22 - a12 * a21

    def solve(rhs):
        return (rhs[:, 0] * a22 - a12 * rhs[:, 1]) / det, (a11 * rhs[:, 1] - rhs[:, 0] * a21) / det

    kb, kg = solve(-r1 * de1)
    # differentiated in phi (de/dtheta = -e):
    # -r1 e1 - r2 e2 kb^2 + r2 de2 kb' + r3 e3 kg^2 - r3 de3 kg' = 0
    dkb, dkg = solve(r1 * e1 + r2 * e2 * (kb ** 2)[:, None] - r3 * e3 * (kg ** 2)[:, None])
    return dict(B=B, C=C, beta=beta, gamma=gamma, k_beta=kb, k_gamma=kg, dk_beta=dkb, dk_gamma=dkg,
                e1=e1, e2=e2, e3=e3, de1=de1, de2=de2, de3=de3)


def _bars(geometry, width, height, rho):
    return [bar(geometry[k], width, height, rho) for k in ("crank", "coupler", "rocker")]


def four_bar_state(t, crank_speed=2 * np.pi, spin_up=1.0, geometry=FOUR_BAR):
    """The four-bar's motion at `t`: the kinematics of four_bar_kinematics, and for each bar
    (crank, coupler, rocker) its centre's position, velocity and acceleration (..., 2) in (x, z)
    and its angle, angular velocity and angular acceleration about +y."""
    phi, w, dw = crank_motion(np.atleast_1d(np.asarray(t, dtype=float)), crank_speed, spin_up)
    k = four_bar_kinematics(phi, geometry)
    r1, r2, r3 = geometry["crank"], geometry["coupler"], geometry["rocker"]
    O, D = np.array(geometry["O"]), np.array(geometry["D"])
    col = lambda x: np.asarray(x)[..., None]  # noqa: E731
    # centre velocity coefficients u = d r_c / d phi and their derivatives u' (de/dtheta = -e)
    u = [0.5 * r1 * k["de1"],
         r1 * k["de1"] + 0.5 * r2 * k["de2"] * col(k["k_beta"]),
         0.5 * r3 * k["de3"] * col(k["k_gamma"])]
    du = [-0.5 * r1 * k["e1"],
          -r1 * k["e1"] + 0.5 * r2 * (-k["e2"] * col(k["k_beta"] ** 2) + k["de2"] * col(k["dk_beta"])),
          0.5 * r3 * (-k["e3"] * col(k["k_gamma"] ** 2) + k["de3"] * col(k["dk_gamma"]))]
    rate = [np.ones_like(phi), k["k_beta"], k["k_gamma"]]
    drate = [np.zeros_like(phi), k["dk_beta"], k["dk_gamma"]]
    centre = [O + 0.5 * r1 * k["e1"], k["B"] + 0.5 * r2 * k["e2"], D + 0.5 * r3 * k["e3"]]
    angle = [phi, k["beta"], k["gamma"]]
    bodies = []
    for i in range(3):
        bodies.append(dict(centre=centre[i], velocity=u[i] * col(w), acceleration=u[i] * col(dw) + du[i] * col(w * w),
                           angle=angle[i], omega=rate[i] * w, alpha=rate[i] * dw + drate[i] * w * w,
                           u=u[i], du=du[i], k=rate[i], dk=drate[i]))
    return dict(kinematics=k, phi=phi, rate=w, acceleration=dw, bodies=bodies)


def four_bar_torque_lagrange(t, crank_speed=2 * np.pi, spin_up=1.0, g=9.81, width=0.01, height=0.02, rho=7850.0,
                             geometry=FOUR_BAR):
    """The driving torque about +y on the crank from Lagrange's equation in the one generalised
    coordinate phi: T = J(phi) phi'^2 / 2 with J = sum_i m_i |u_i|^2 + I_i k_i^2 (u_i = d r_ci /
    d phi, k_i = d theta_i / d phi), V = g sum_i m_i z_ci, and
    tau = d/dt(dT/dphi') - dT/dphi + dV/dphi = J phi'' + J'(phi) phi'^2 / 2 + g sum_i m_i u_iz,
    J' = sum_i 2 m_i u_i . u_i' + 2 I_i k_i k_i'."""
    s = four_bar_state(t, crank_speed, spin_up, geometry)
    J = dJ = dV = 0.0
    for (m, inertia), b in zip(_bars(geometry, width, height, rho), s["bodies"]):
        J = J + m * np.sum(b["u"] ** 2, axis=-1) + inertia * b["k"] ** 2
        dJ = dJ + 2 * m * np.sum(b["u"] * b["du"], axis=-1) + 2 * inertia * b["k"] * b["dk"]
        dV = dV + m * g * b["u"][..., 1]
    return J * s["acceleration"] + 0.5 * dJ * s["rate"] ** 2 + dV


def four_bar_torque_newton_euler(t, crank_speed=2 * np.pi, spin_up=1.0, g=9.81, width=0.01, height=0.02,
                                 rho=7850.0, geometry=FOUR_BAR):
    """The same torque from the three bars' Newton-Euler equations with the joint forces as
    unknowns (9 equations, 9 unknowns per sample): F_O the ground's force on the crank at O,
    F_B the crank's on the coupler at B, F_C the coupler's on the rocker at C, F_D the ground's
    on the rocker at D, and tau the ground's torque about +y on the crank:

        crank   m1 a1 = F_O - F_B + m1 g,  I1 alpha1 = M(O - c1, F_O) - M(B - c1, F_B) + tau
        coupler m2 a2 = F_B - F_C + m2 g,  I2 alpha2 = M(B - c2, F_B) - M(C - c2, F_C)
        rocker  m3 a3 = F_C + F_D + m3 g,  I3 alpha3 = M(C - c3, F_C) + M(D - c3, F_D)

    with M(r, F) = r_z F_x - r_x F_z, g = (0, -g) in (x, z). Returns (tau, the joint forces
    (..., 4, 2): F_O, F_B, F_C, F_D)."""
    s = four_bar_state(t, crank_speed, spin_up, geometry)
    k = s["kinematics"]
    O, D = np.array(geometry["O"]), np.array(geometry["D"])
    shape = np.shape(s["phi"])
    B, C = np.reshape(k["B"], (-1, 2)), np.reshape(k["C"], (-1, 2))
    n = len(B)
    bodies = s["bodies"]
    props = _bars(geometry, width, height, rho)
    A = np.zeros((n, 9, 9))
    rhs = np.zeros((n, 9))
    gvec = np.array([0.0, -g])

    def moment_row(r):  # coefficients of (F_x, F_z) in M(r, F)
        return np.stack([r[:, 1], -r[:, 0]], axis=-1)

    # unknowns: F_O (0, 1), F_B (2, 3), F_C (4, 5), F_D (6, 7), tau (8)
    sign = {0: [(0, 1.0), (1, -1.0)], 1: [(1, 1.0), (2, -1.0)], 2: [(2, 1.0), (3, 1.0)]}
    points = {0: np.broadcast_to(O, (n, 2)), 1: B, 2: C, 3: np.broadcast_to(D, (n, 2))}
    joint_point = {0: [0, 1], 1: [1, 2], 2: [2, 3]}  # bar i carries joints (its ends)
    for i, ((m, inertia), b) in enumerate(zip(props, bodies)):
        c = np.reshape(b["centre"], (-1, 2))
        a = np.reshape(b["acceleration"], (-1, 2))
        alpha = np.reshape(b["alpha"], -1)
        for (j, sg), p in zip(sign[i], joint_point[i]):
            for comp in range(2):
                A[:, 3 * i + comp, 2 * j + comp] = sg
            A[:, 3 * i + 2, 2 * j:2 * j + 2] = sg * moment_row(points[p] - c)
        rhs[:, 3 * i:3 * i + 2] = m * (a - gvec)
        rhs[:, 3 * i + 2] = inertia * alpha
    A[:, 2, 8] = 1.0
    x = np.linalg.solve(A, rhs[..., None])[..., 0]
    return x[:, 8].reshape(shape), x[:, :8].reshape(shape + (4, 2))


def four_bar_energy(t, crank_speed=2 * np.pi, spin_up=1.0, g=9.81, width=0.01, height=0.02, rho=7850.0,
                    geometry=FOUR_BAR):
    """The kinetic plus potential energy of the three bars at `t`, from their centres' velocities
    and their angular velocities: sum_i m_i |v_i|^2 / 2 + I_i omega_i^2 / 2 + m_i g z_ci."""
    s = four_bar_state(t, crank_speed, spin_up, geometry)
    energy = 0.0
    for (m, inertia), b in zip(_bars(geometry, width, height, rho), s["bodies"]):
        energy = energy + 0.5 * m * np.sum(b["velocity"] ** 2, axis=-1) + 0.5 * inertia * b["omega"] ** 2 \
            + m * g * b["centre"][..., 1]
    return energy


def rigid_four_bar(t, crank_speed=2 * np.pi, spin_up=1.0, g=9.81):
    """The planar four-bar of rigid bars, all pivots about world y, in the x-z plane, gravity -z.

    Geometry: ground pivots O = (0, 0, 0) and D = (1, 0, 0); crank O -> B, 0.25 m; coupler
    B -> C, 1.0 m; rocker D -> C, 0.75 m (a Grashof crank-rocker). The crank's angle phi about
    +y is prescribed (crank_motion): B = 0.25 (cos phi, 0, -sin phi), phi(0) = 0 (B = (0.25, 0,
    0)), rate crank_speed (1 - cos(pi t / spin_up)) / 2 until spin_up, then crank_speed. C is
    the closure point on the branch with z > 0 at t = 0: C(0) = (0.916667, 0, 0.745356).

    Bodies: uniform steel bars (rho 7850) of cross-section 0.01 (y) x 0.02 (in-plane height h),
    moment of inertia about the centre for rotation about y m (L^2 + h^2) / 12.

    Returns (len(t), 4) per sample: the rocker's angle about +y from its initial direction
    D -> C(0) [rad]; C's x and z [m]; the driving torque about +y that the ground applies to the
    crank to impose the prescribed motion [N m] (Lagrange's equation in phi,
    four_bar_torque_lagrange; four_bar_torque_newton_euler is the check). At t = 0, at rest,
    it holds the mechanism against gravity."""
    t = np.asarray(t, dtype=float)
    phi, _, _ = crank_motion(t, crank_speed, spin_up)
    k = four_bar_kinematics(phi)
    gamma0 = four_bar_kinematics(np.array([0.0]))["gamma"][0]
    rocker = np.angle(np.exp(1j * (k["gamma"] - gamma0)))  # the rocker swings less than pi
    tau = four_bar_torque_lagrange(t, crank_speed, spin_up, g)
    return np.column_stack([rocker, k["C"][:, 0], k["C"][:, 1], tau])


def four_bar_coupler_deflection(t, E=2.0e11, crank_speed=2 * np.pi, spin_up=1.0, g=9.81, width=0.01, height=0.02,
                                rho=7850.0, geometry=FOUR_BAR):
    """The quasi-static mid-span deflection of a flexible coupler (a uniform beam pinned at B and
    C, bending in the plane, I = width height^3 / 12) under its weight and the d'Alembert loads
    of the rigid motion: the transverse load per length is linear along the coupler (the rigid
    body's acceleration field is), and only its mean q moves the mid-span of a pinned beam:
    w = 5 q L^4 / (384 E I), q = m (g - a_c) . n / L, a_c the coupler's centre's acceleration,
    g = (0, -g), n = u x y = (-u_z, u_x) in (x, z) for the unit chord u = (C - B) / L (at t = 0
    (-0.745, 0.667), up and back). Returns w along n [m] at `t` (negative: sagging)."""
    s = four_bar_state(t, crank_speed, spin_up, geometry)
    k = s["kinematics"]
    L = geometry["coupler"]
    u = (k["C"] - k["B"]) / L
    n = np.stack([-u[:, 1], u[:, 0]], axis=-1)
    m, _ = bar(L, width, height, rho)
    q = m * np.sum((np.array([0.0, -g]) - s["bodies"][1]["acceleration"]) * n, axis=-1) / L
    return 5 * q * L ** 4 / (384 * E * width * height ** 3 / 12)
