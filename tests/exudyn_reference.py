"""An independent reference for connected flexible bodies: the FE mass and stiffness matrices of
the same mesh from CalculiX (`*FREQUENCY, SOLVER=MATRIXSTORAGE`), not from the builder's
element code, and the multibody model in Exudyn (PyPI `exudyn`): its floating-frame bodies
(ObjectFFRFreducedOrder) with its own Hurty-Craig-Bampton modes (RBE2 interfaces on the flange
faces), its rigid-face markers and its joints, integrated by its generalised-alpha solver.
Nothing of the builder, the FMUs or the co-simulation master is used.

    t, positions = double_pendulum(deck_text, workdir)
    # one row per millisecond from t = 0: elbow x, z and tip x, z (world)
    t, rows = slider_crank(deck_text, workdir, pin)
    # one row per millisecond from t = 0: the rod's tip x, z and the slider's load on it (z)
    t, positions = pendulum_chain(deck_text, workdir, n_links=3)
    # one row per millisecond from t = 0: each link's tip x, z (world)
    t, rows = four_bar(deck_text, workdir)
    # one row per millisecond from t = 0: rocker angle, C x, z, the crank's torque, the
    # coupler's mid-span deflection (the rigid theory of the same scenes: rigid_mechanisms.py)

Exudyn's pitfalls met on the way (Exudyn 1.13.6): spectral radius 1.0 stopped Newton converging
at t = 7..9 s of the double pendulum, and Exudyn then cuts its step silently (runs of ten
minutes); 0.9 runs clean. A Newton tolerance below the default 1e-8 stalls (K ~ 1e11). Nodes
of no element (the deck's flange reference nodes) must stay out of the FE model, or M is
singular. The first boundary list is fixed to the floating frame. Exudyn's static solver runs a
pseudo-time from 0 to 1 through the joints' user functions. Two runs of the same model differ
by ~2e-10 m (the double pendulum, 2 s): Exudyn is not bit-reproducible run to run. GenericJoint's
ForceLocal is the force on marker 0, but the rotational parts of TorqueLocal are multipliers of
constraints like t_z0 . t_x1 = 0 and act on marker 1 with the sign as printed (four_bar's drive).
A drive by GenericJoint's rotational offset (Tait-Bryan angles added to marker 0's frame) turns
through any number of revolutions; offsetUserFunction_t is not implemented in this version, so
the drive starts at rest with zero acceleration. Constraint multipliers of the index-3
generalised-alpha solver alternate from step to step at ~1e-3 of their swing and ring for the
first ~50 ms after a start out of equilibrium."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from calculix import ccx_executable, node_coordinates, node_set

#: output period of the returned trajectories [s]
SAMPLE = 1e-3


def _upper_triangle(path: Path, n: int) -> sp.csr_matrix:
    """CalculiX writes the upper triangle (row <= column, 1-based): mirrored here."""
    data = np.loadtxt(path)
    r, c, v = data[:, 0].astype(int) - 1, data[:, 1].astype(int) - 1, data[:, 2]
    if np.any(r > c):
        raise RuntimeError(f"{path.name}: expected the upper triangle only")
    off = r != c
    return sp.csr_matrix((np.concatenate([v, v[off]]), (np.concatenate([r, c[off]]), np.concatenate([c, r[off]]))),
                         shape=(n, n))


def ccx_matrices(deck_text: str, workdir):
    """(node positions, node ids, M, K), three DoFs per node in the deck's *NODE order; nodes of
    no element (CalculiX gives them no DoF) are left out."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    job = "matrices"
    (workdir / f"{job}.inp").write_text(deck_text.rstrip("\n") + "\n*STEP\n*FREQUENCY, SOLVER=MATRIXSTORAGE\n*END STEP\n")
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
    res = subprocess.run([ccx_executable(), job], cwd=workdir, capture_output=True, text=True, env=env, timeout=600)
    if res.returncode != 0 or not (workdir / f"{job}.sti").exists():
        raise RuntimeError(f"ccx failed:\n{res.stdout[-2000:]}\n{res.stderr[-2000:]}")
    # .dof: one "node.direction" label per matrix row, in CalculiX's own order
    labels = (workdir / f"{job}.dof").read_text().split()
    dof_node = np.array([int(s.split(".")[0]) for s in labels])
    dof_dir = np.array([int(s.split(".")[1]) for s in labels])
    n = len(labels)
    mass, stiffness = _upper_triangle(workdir / f"{job}.mas", n), _upper_triangle(workdir / f"{job}.sti", n)
    coords = node_coordinates(deck_text)
    present = set(dof_node.tolist())
    ids = [i for i in coords if i in present]
    if len(ids) * 3 != n:
        raise RuntimeError("CalculiX did not write three DoFs per node")
    index = {nid: k for k, nid in enumerate(ids)}
    ours = np.array([3 * index[a] + (d - 1) for a, d in zip(dof_node, dof_dir)])
    p = sp.csr_matrix((np.ones(n), (ours, np.arange(n))), shape=(n, n))
    return np.array([coords[i] for i in ids]), ids, (p @ mass @ p.T).tocsr(), (p @ stiffness @ p.T).tocsr()


def rotation_y(degrees):
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


class _FlexibleLink:
    """The link's CalculiX matrices turned into Exudyn's Craig-Bampton floating-frame body
    template (RBE2 faces BASE and TIP, `modes` fixed-interface eigenmodes), with the faces'
    centres in the body frame."""

    def __init__(self, deck_text, workdir, modes, matrices=None):
        from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface, HCBstaticModeSelection

        pos, ids, M, K = matrices or ccx_matrices(deck_text, workdir)
        index = {nid: k for k, nid in enumerate(ids)}
        self.pos = pos
        self.base = [index[i] for i in node_set(deck_text, "BASE")]
        self.tip = [index[i] for i in node_set(deck_text, "TIP")]
        fem = FEMinterface()
        fem.nodes = {"Position": pos}
        fem.massMatrix = M  # FEMinterface stores scipy CSR directly (not the old triplet arrays)
        fem.stiffnessMatrix = K
        # RBE2 with excludeRigidBodyMotion: BASE face is rigidly fixed to the floating frame, TIP
        # face moves rigidly (6 static modes) + `modes` fixed-interface eigenmodes.
        fem.ComputeHurtyCraigBamptonModes(boundaryNodesList=[self.base, self.tip], nEigenModes=modes,
                                          useSparseSolver=True, computationMode=HCBstaticModeSelection.RBE2)
        self.cms = ObjectFFRFreducedOrderInterface(fem)
        self.base_c = pos[self.base].mean(axis=0)  # face centres in the body frame (local)
        self.tip_c = pos[self.tip].mean(axis=0)

    def add(self, mbs, origin, rotation, damping_beta, name):
        b = self.cms.AddObjectFFRFreducedOrder(mbs, positionRef=list(origin), rotationMatrixRef=rotation,
                                               stiffnessProportionalDamping=damping_beta,
                                               gravity=[0.0, 0.0, -9.81], name=name)
        return b["oFFRFreducedOrder"]

    def face_marker(self, mbs, body, nodes):
        import exudyn.itemInterface as ei

        # uniform weights: faces are rigid under RBE2 modes, so the weighting only sets the
        # marker origin (the face centre by symmetry), not its motion
        w = np.ones(len(nodes)) / len(nodes)
        return mbs.AddMarker(ei.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(nodes),
                                                        weightingFactors=w))

    def node_sensor(self, mbs, body, point):
        """A world-position sensor on the mesh node at `point` (body frame); there must be one."""
        import exudyn as exu
        import exudyn.itemInterface as ei

        k = int(np.argmin(np.linalg.norm(self.pos - np.asarray(point, dtype=float), axis=1)))
        if np.linalg.norm(self.pos[k] - point) > 1e-9:
            raise RuntimeError(f"no mesh node at {point}")
        return mbs.AddSensor(ei.SensorSuperElement(bodyNumber=body, meshNodeNumber=k,
                                                   outputVariableType=exu.OutputVariableType.Position,
                                                   storeInternal=True, writeToFile=False))

    def tip_sensor(self, mbs, body):
        """A position sensor on the mesh node at the tip face's centre (the face is rigid, so it
        moves as the face's marker)."""
        import exudyn as exu
        import exudyn.itemInterface as ei

        nodes, c = self.tip, self.tip_c
        k = nodes[int(np.argmin(np.linalg.norm(self.pos[nodes] - c, axis=1)))]
        if np.linalg.norm(self.pos[k] - c) > 1e-9:
            raise RuntimeError("no mesh node at the face centre")
        return mbs.AddSensor(ei.SensorSuperElement(bodyNumber=body, meshNodeNumber=k,
                                                   outputVariableType=exu.OutputVariableType.Position,
                                                   storeInternal=True, writeToFile=False))


def _settings(seconds, step, spectral_radius, modified_newton, verbose):
    import exudyn as exu

    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = int(round(seconds / step))
    s.timeIntegration.endTime = seconds
    # rho_inf = 1 (no numerical damping) drifts into Newton failures and step cuts after ~7 s
    # (index-3 joints on a stiff FFRF body); 0.9 runs through, and halving the step changes the
    # result by < 4e-5 of the swing
    s.timeIntegration.generalizedAlpha.spectralRadius = spectral_radius
    s.timeIntegration.newton.useModifiedNewton = modified_newton  # reuse Jacobian: faster, same result
    s.timeIntegration.verboseMode = 1 if verbose else 0
    s.staticSolver.verboseMode = 1 if verbose else 0
    # tighter than the default 1e-8 stagnates near 4e-9 (round-off with K ~ 1e11) and makes the
    # solver cut the step size to 6e-5 s for the rest of the run
    s.timeIntegration.newton.relativeTolerance = 1e-8
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.5 * step  # record every step; resampled below
    s.show.statistics = verbose
    return s


def _every_sample(data, seconds, step, columns):
    """Rows of a sensor's stored data at every SAMPLE from t = 0 (the step divides it)."""
    t_out = np.arange(int(round(seconds / SAMPLE)) + 1) * SAMPLE
    idx = np.searchsorted(data[:, 0], t_out - 0.25 * step)
    if idx.max() >= len(data) or np.abs(data[idx, 0] - t_out).max() > 1e-9:
        raise RuntimeError("sensor times do not hit every ms (step must divide 1 ms)")
    return t_out, data[idx][:, columns]


def pendulum_chain(deck_text: str, workdir, n_links=3, pivot_deg=45.0, seconds=12.0, step=1e-3, modes=12,
                   damping_beta=1e-3, spectral_radius=0.9, modified_newton=True, verbose=False, matrices=None):
    """(t, positions): t every 1 ms from 0, positions (len(t), 2 n_links) = the tip face centre
    (x, z, world) of link 1, 2, ..., n_links in turn (the joints, then the chain's tip).

    n_links copies of the link (the deck's mesh, one Craig-Bampton body each) hung end to end:
    link 1's BASE face centre on the world origin, link k+1's BASE face on link k's TIP face, by
    revolute joints about world y (GenericJoint, rotation about the joint's y free, the rest
    held; the face markers are RBE2-rigid). All links start straight and in line, their local x
    axis turned by rotation_y(pivot_deg) (x -> (cos, 0, -sin): pivot_deg below the horizontal,
    i.e. at pi/2 - pivot_deg from the downward vertical towards +x), at rest, undeformed (no
    static pre-solve); gravity -z (9.81). Generalised-alpha at `step` (index 3)."""
    import exudyn as exu
    import exudyn.itemInterface as ei

    link = _FlexibleLink(deck_text, workdir, modes, matrices)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    A = rotation_y(pivot_deg)
    bodies = []
    origin = np.zeros(3) - A @ link.base_c  # place body 1's base face centre at the world origin
    for k in range(n_links):
        bodies.append(link.add(mbs, origin, A, damping_beta, f"link{k + 1}"))
        origin = origin + A @ (link.tip_c - link.base_c)

    ground = mbs.AddObject(ei.ObjectGround())
    # revolute about world y: the ground marker frame is turned like the body's initial frame so
    # the joint starts with zero relative rotation (Ry leaves y unchanged); rotationMarker0 of
    # GenericJoint does the same but is deprecated in this Exudyn in favour of the marker's localHT
    previous = mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=ground, localHT=exu.HT(rotation=A, translation=[0, 0, 0])))
    markers = [previous]
    for k, b in enumerate(bodies):
        markers.append(link.face_marker(mbs, b, link.base))
        if k + 1 < n_links:
            markers.append(link.face_marker(mbs, b, link.tip))
    for k in range(n_links):
        mbs.AddObject(ei.GenericJoint(markerNumbers=markers[2 * k:2 * k + 2], constrainedAxes=[1, 1, 1, 1, 0, 1]))
    sensors = [link.tip_sensor(mbs, b) for b in bodies]
    mbs.Assemble()
    mbs.SolveDynamic(_settings(seconds, step, spectral_radius, modified_newton, verbose))

    columns = []
    for k in sensors:
        t_out, xz = _every_sample(mbs.GetSensorStoredData(k), seconds, step, [1, 3])
        columns.append(xz)
    return t_out, np.hstack(columns)


def double_pendulum(deck_text: str, workdir, pivot_deg=45.0, seconds=12.0, step=1e-3, modes=12,
                    damping_beta=1e-3, spectral_radius=0.9, modified_newton=True, verbose=False, matrices=None):
    """(t, positions): t every 1 ms from 0, positions (n, 4) = elbow x, z, tip x, z (world).

    Both links start straight in line, local x rotated by rotation_y(pivot_deg), at rest; gravity
    -z: pendulum_chain with two links."""
    return pendulum_chain(deck_text, workdir, 2, pivot_deg, seconds, step, modes, damping_beta, spectral_radius,
                          modified_newton, verbose, matrices)


def slider_crank(deck_text: str, workdir, pin, seconds=6.0, step=1e-3, modes=12, damping_beta=1e-3,
                 spectral_radius=0.9, modified_newton=True, verbose=False, matrices=None):
    """(t, rows): t every 1 ms from 0, rows (n, 3) = the rod's tip x, z and the slider's load
    on the rod along z (world).

    The link is the connecting rod: its BASE face's centre is forced to the crank pin's position
    `pin(t)` (a 3-vector, world; the crank's law is the scene's, given) with the rotations
    about x and z held and the one about y free (a revolute joint about y on the pin); its TIP
    face's centre is held on the world x axis (y = z = 0; a frictionless slider). The rod starts
    along +x from pin(0), in static equilibrium (Exudyn's static solve under gravity at t = 0),
    and the dynamic run starts from there."""
    import exudyn as exu
    import exudyn.itemInterface as ei

    link = _FlexibleLink(deck_text, workdir, modes, matrices)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    start = np.asarray(pin(0.0), dtype=float)
    rod = link.add(mbs, start - link.base_c, np.eye(3), damping_beta, "rod")
    ground = mbs.AddObject(ei.ObjectGround())
    m_ground = mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    m_base, m_tip = link.face_marker(mbs, rod, link.base), link.face_marker(mbs, rod, link.tip)

    # Exudyn's static solver runs its load steps in a pseudo-time from 0 to 1, which the user
    # function would read as the crank's time: it sees t = 0 until the dynamic run starts
    clock = {"static": True}

    def pin_offset(mbs_, t, item, parameters):
        return [*np.asarray(pin(0.0 if clock["static"] else t), dtype=float), 0.0, 0.0, 0.0]

    mbs.AddObject(ei.GenericJoint(markerNumbers=[m_ground, m_base], constrainedAxes=[1, 1, 1, 1, 0, 1],
                                  offsetUserFunction=pin_offset))
    slider = mbs.AddObject(ei.GenericJoint(markerNumbers=[m_ground, m_tip], constrainedAxes=[0, 1, 1, 0, 0, 0]))
    tip = link.tip_sensor(mbs, rod)
    # the joint's force in the joint frame (marker 0's, here the world's axes); its sign is the
    # force on marker 0, the ground: at the static start it reads -m g / 2 under the rod's weight
    load = mbs.AddSensor(ei.SensorObject(objectNumber=slider, outputVariableType=exu.OutputVariableType.ForceLocal,
                                         storeInternal=True, writeToFile=False))
    mbs.Assemble()
    s = _settings(seconds, step, spectral_radius, modified_newton, verbose)
    mbs.SolveStatic(s)
    clock["static"] = False
    mbs.systemData.SetODE2Coordinates(mbs.systemData.GetODE2Coordinates(), configuration=exu.ConfigurationType.Initial)
    mbs.SolveDynamic(s)
    t_out, xz = _every_sample(mbs.GetSensorStoredData(tip), seconds, step, [1, 3])
    _, fz = _every_sample(mbs.GetSensorStoredData(load), seconds, step, [3])
    return t_out, np.hstack([xz, -fz])


def _crank_angle(t, crank_speed, spin_up):
    """The four-bar's prescribed crank angle: the integral from 0 of the rate
    crank_speed (1 - cos(pi t / spin_up)) / 2 until spin_up, crank_speed after."""
    if t < spin_up:
        return 0.5 * crank_speed * (t - spin_up / np.pi * np.sin(np.pi * t / spin_up))
    return 0.5 * crank_speed * spin_up + crank_speed * (t - spin_up)


def four_bar(deck_text: str, workdir, seconds=6.0, step=1e-3, modes=12, damping_beta=1e-3, spectral_radius=0.9,
             crank_speed=2 * np.pi, spin_up=1.0, modified_newton=True, verbose=False, matrices=None):
    """(t, rows): t every 1 ms from 0, rows (len(t), 5) = the rocker's angle about +y from its
    initial direction D -> C [rad], C's x and z [m] (the coupler's TIP face centre, world), the
    driving torque about +y that the ground applies TO the crank [N m], and the coupler's
    mid-span deflection [m] (below).

    The planar four-bar of tests/rigid_mechanisms.py (rigid_four_bar), in the world x-z plane,
    gravity -z (9.81): ground pivots O = (0, 0, 0) and D = (1, 0, 0), crank O -> B 0.25 m,
    coupler B -> C 1.0 m, rocker D -> C 0.75 m; at t = 0 B = (0.25, 0, 0) and C = (0.916667, 0,
    0.745356) (the closure with z > 0). The COUPLER is the flexible link of the deck (one
    Craig-Bampton body, `modes` fixed-interface modes): its BASE face centre on B and its TIP
    face centre on C, its local x axis turned about y to point from B to C (rotation_y of
    -48.19 deg), straight. Crank and rocker are rigid (Exudyn RigidBody, Euler parameters):
    uniform steel boxes L x 0.01 (y) x 0.02 (in-plane), rho 7850 (InertiaCuboid: about y
    m (L^2 + 0.02^2) / 12), their local x along O -> B and D -> C.

    Joints (17 constraint equations on 18 rigid-body coordinates, the drive the 18th; none
    redundant): ground-crank at O a GenericJoint with all six axes held and the rotational
    offset (0, phi(t), 0) (Tait-Bryan angles added to the ground's joint frame: the crank's
    frame is Ry(phi), so B = 0.25 (cos phi, 0, -sin phi)), phi(t) the integral of
    crank_speed (1 - cos(pi t / spin_up)) / 2 until spin_up, crank_speed after (as
    rigid_mechanisms.crank_motion); crank-coupler SPHERICAL at B (GenericJoint, translations
    held, crank end marker and the coupler's BASE face marker); coupler-rocker UNIVERSAL at C
    (GenericJoint with marker 0 the rocker's end, marker 1 the coupler's TIP face, translations
    held and the one rotation constraint t_y(rocker) . t_z(coupler TIP face) = 0: the
    rotation about the coupler's own long axis locked, the other two free); rocker-ground
    revolute about y at D (rotation about the joint's y free). Everything starts at rest in
    this configuration, the coupler straight and undeformed (no static pre-solve).
    Generalised-alpha at `step` (index 3).

    Outputs: the rocker's angle from its rotation matrix R (atan2(R_02, R_00) minus its initial
    value, wrapped to (-pi, pi]); the torque is the drive joint's reaction about y: the y
    component of Exudyn's TorqueLocal of this fully held GenericJoint is the multiplier of its
    constraint t_z0 . t_x1 = 0, which turns marker 1 (the crank) by +lambda about y (where the
    translational ForceLocal is the force on marker 0, the ground: the two differ in sign), so it
    is the torque on the crank as it stands (the user function's Ry(phi) leaves y alone). Checked
    at rest under gravity: the crank's and the coupler's weights turn the crank about +y, and
    the torque reads negative (-2.62 N m at t = 0.05 s, the rigid theory's -2.624). The
    deflection is the coupler's mid-span centre-line node minus the midpoint of
    its BASE and TIP face centres, along the chord's normal u x y (u the unit chord B -> C; at
    t = 0 the coupler's local +z, (-0.745, 0, 0.667))."""
    import exudyn as exu
    import exudyn.itemInterface as ei
    from exudyn.utilities import InertiaCuboid

    O, D = np.zeros(3), np.array([1.0, 0.0, 0.0])
    r1, r2, r3 = 0.25, 1.0, 0.75
    B = np.array([r1, 0.0, 0.0])
    # C: |C - B| = r2, |C - D| = r3, z > 0
    cx = (r2 ** 2 - r3 ** 2 - B[0] ** 2 + D[0] ** 2) / (2 * (D[0] - B[0]))
    C = np.array([cx, 0.0, np.sqrt(r3 ** 2 - (cx - D[0]) ** 2)])

    def turned(u):  # the rotation about y turning x onto the unit vector u (in the x-z plane)
        return rotation_y(np.degrees(np.arctan2(-u[2], u[0])))

    A_coupler, A_rocker = turned((C - B) / r2), turned((C - D) / r3)
    gamma0 = np.arctan2(A_rocker[0, 2], A_rocker[0, 0])

    link = _FlexibleLink(deck_text, workdir, modes, matrices)
    if abs(np.linalg.norm(link.tip_c - link.base_c) - r2) > 1e-12:
        raise ValueError("the coupler's face centres are not 1 m apart")
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    gravity = [0.0, 0.0, -9.81]
    coupler = link.add(mbs, B - A_coupler @ link.base_c, A_coupler, damping_beta, "coupler")
    crank = mbs.CreateRigidBody(inertia=InertiaCuboid(7850.0, [r1, 0.01, 0.02]), referencePosition=list(0.5 * (O + B)),
                                referenceRotationMatrix=np.eye(3), gravity=gravity, name="crank")
    rocker = mbs.CreateRigidBody(inertia=InertiaCuboid(7850.0, [r3, 0.01, 0.02]),
                                 referencePosition=list(0.5 * (D + C)), referenceRotationMatrix=A_rocker,
                                 gravity=gravity, name="rocker")
    ground = mbs.AddObject(ei.ObjectGround())

    def rigid_marker(body, position, rotation=np.eye(3)):
        return mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=body, localHT=exu.HT(rotation=rotation,
                                                                                translation=list(position))))

    # Exudyn's static solver is not used here, so the user function sees the dynamic run's time only
    def drive_offset(mbs_, t, item, parameters):
        return [0.0, 0.0, 0.0, 0.0, _crank_angle(t, crank_speed, spin_up), 0.0]

    drive = mbs.AddObject(ei.GenericJoint(markerNumbers=[rigid_marker(ground, O), rigid_marker(crank, [-r1 / 2, 0, 0])],
                                          constrainedAxes=[1, 1, 1, 1, 1, 1], offsetUserFunction=drive_offset))
    base, tip = link.face_marker(mbs, coupler, link.base), link.face_marker(mbs, coupler, link.tip)
    mbs.AddObject(ei.GenericJoint(markerNumbers=[rigid_marker(crank, [r1 / 2, 0, 0]), base],
                                  constrainedAxes=[1, 1, 1, 0, 0, 0]))
    # universal: [1, 0, 0] on the rotations holds t_y0 . t_z1 = 0 (Exudyn's GenericJoint)
    mbs.AddObject(ei.GenericJoint(markerNumbers=[rigid_marker(rocker, [r3 / 2, 0, 0]), tip],
                                  constrainedAxes=[1, 1, 1, 1, 0, 0]))
    mbs.AddObject(ei.GenericJoint(markerNumbers=[rigid_marker(ground, D, A_rocker),
                                                 rigid_marker(rocker, [-r3 / 2, 0, 0])],
                                  constrainedAxes=[1, 1, 1, 1, 0, 1]))

    tip_sensor = link.tip_sensor(mbs, coupler)
    base_sensor = link.node_sensor(mbs, coupler, link.base_c)
    mid_sensor = link.node_sensor(mbs, coupler, 0.5 * (link.base_c + link.tip_c))
    rotation = mbs.AddSensor(ei.SensorBody(bodyNumber=rocker, outputVariableType=exu.OutputVariableType.RotationMatrix,
                                           storeInternal=True, writeToFile=False))
    torque = mbs.AddSensor(ei.SensorObject(objectNumber=drive, outputVariableType=exu.OutputVariableType.TorqueLocal,
                                           storeInternal=True, writeToFile=False))
    mbs.Assemble()
    mbs.SolveDynamic(_settings(seconds, step, spectral_radius, modified_newton, verbose))

    t_out, c_xz = _every_sample(mbs.GetSensorStoredData(tip_sensor), seconds, step, [1, 3])
    _, R = _every_sample(mbs.GetSensorStoredData(rotation), seconds, step, [1, 3])  # R_00, R_02
    angle = np.angle(np.exp(1j * (np.arctan2(R[:, 1], R[:, 0]) - gamma0)))
    _, m_y = _every_sample(mbs.GetSensorStoredData(torque), seconds, step, [2])
    _, p_base = _every_sample(mbs.GetSensorStoredData(base_sensor), seconds, step, [1, 3])
    _, p_mid = _every_sample(mbs.GetSensorStoredData(mid_sensor), seconds, step, [1, 3])
    chord = c_xz - p_base
    chord /= np.linalg.norm(chord, axis=1)[:, None]
    normal = np.column_stack([-chord[:, 1], chord[:, 0]])  # u x y in (x, z)
    deflection = np.sum((p_mid - 0.5 * (p_base + c_xz)) * normal, axis=1)
    return t_out, np.column_stack([angle, c_xz, m_y[:, 0], deflection])
