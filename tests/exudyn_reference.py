"""An independent reference for connected flexible bodies: the FE mass and stiffness matrices of
the same mesh from CalculiX (`*FREQUENCY, SOLVER=MATRIXSTORAGE`), not from the builder's
element code, and the multibody model in Exudyn (PyPI `exudyn`): its floating-frame bodies
(ObjectFFRFreducedOrder) with its own Hurty-Craig-Bampton modes (RBE2 interfaces on the flange
faces), its rigid-face markers and its joints, integrated by its generalised-alpha solver.
Nothing of the builder, the FMUs or the co-simulation master is used.

    t, positions = double_pendulum(deck_text, workdir)
    # one row per millisecond from t = 0: elbow x, z and tip x, z (world)

Exudyn's pitfalls met on the way (Exudyn 1.13.6): spectral radius 1.0 stopped Newton converging
at t = 7..9 s of the double pendulum, and Exudyn then cuts its step silently (runs of ten
minutes); 0.9 runs clean. A Newton tolerance below the default 1e-8 stalls (K ~ 1e11). Nodes
of no element (the deck's flange reference nodes) must stay out of the FE model, or M is
singular. The first boundary list is fixed to the floating frame."""

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


def double_pendulum(deck_text: str, workdir, pivot_deg=45.0, seconds=12.0, step=1e-3, modes=12,
                    damping_beta=1e-3, spectral_radius=0.9, modified_newton=True, verbose=False, matrices=None):
    """(t, positions): t every 1 ms from 0, positions (n, 4) = elbow x, z, tip x, z (world).

    Both links start straight in line, local x rotated by rotation_y(pivot_deg), at rest; gravity -z."""
    import exudyn as exu
    import exudyn.itemInterface as ei
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface, HCBstaticModeSelection

    pos, ids, M, K = matrices or ccx_matrices(deck_text, workdir)
    index = {nid: k for k, nid in enumerate(ids)}
    base = [index[i] for i in node_set(deck_text, "BASE")]
    tip = [index[i] for i in node_set(deck_text, "TIP")]

    fem = FEMinterface()
    fem.nodes = {"Position": pos}
    fem.massMatrix = M  # FEMinterface stores scipy CSR directly (not the old triplet arrays)
    fem.stiffnessMatrix = K
    # RBE2 with excludeRigidBodyMotion: BASE face is rigidly fixed to the floating frame, TIP
    # face moves rigidly (6 static modes) + `modes` fixed-interface eigenmodes.
    fem.ComputeHurtyCraigBamptonModes(boundaryNodesList=[base, tip], nEigenModes=modes,
                                      useSparseSolver=True,
                                      computationMode=HCBstaticModeSelection.RBE2)
    cms = ObjectFFRFreducedOrderInterface(fem)

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    A = rotation_y(pivot_deg)
    L = pos[tip].mean(axis=0)[0] - pos[base].mean(axis=0)[0]
    base_c = pos[base].mean(axis=0)  # face centres in the body frame (local)
    tip_c = pos[tip].mean(axis=0)
    g = [0.0, 0.0, -9.81]

    bodies = []
    origin = np.zeros(3) - A @ base_c  # place body 1's base face centre at the world origin
    for k in range(2):
        b = cms.AddObjectFFRFreducedOrder(mbs, positionRef=list(origin), rotationMatrixRef=A,
                                          stiffnessProportionalDamping=damping_beta,
                                          gravity=g, name=f"link{k + 1}")
        bodies.append(b["oFFRFreducedOrder"])
        origin = origin + A @ (tip_c - base_c)

    def face_marker(body, nodes):
        # uniform weights: faces are rigid under RBE2 modes, so the weighting only sets the
        # marker origin (the face centre by symmetry), not its motion
        w = np.ones(len(nodes)) / len(nodes)
        return mbs.AddMarker(ei.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(nodes),
                                                        weightingFactors=w))

    ground = mbs.AddObject(ei.ObjectGround())
    # revolute about world y: the ground marker frame is turned like the body's initial frame so
    # the joint starts with zero relative rotation (Ry leaves y unchanged); rotationMarker0 of
    # GenericJoint does the same but is deprecated in this Exudyn in favour of the marker's localHT
    m_ground = mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=ground, localHT=exu.HT(rotation=A, translation=[0, 0, 0])))
    m_base1, m_tip1 = face_marker(bodies[0], base), face_marker(bodies[0], tip)
    m_base2, m_tip2 = face_marker(bodies[1], base), face_marker(bodies[1], tip)
    mbs.AddObject(ei.GenericJoint(markerNumbers=[m_ground, m_base1], constrainedAxes=[1, 1, 1, 1, 0, 1]))
    mbs.AddObject(ei.GenericJoint(markerNumbers=[m_tip1, m_base2], constrainedAxes=[1, 1, 1, 1, 0, 1]))

    # sensors on the face-centre mesh nodes (exist in the 2x2 quadratic face mesh); the face is
    # rigid, so this equals the marker position
    def centre_node(nodes, c):
        k = nodes[int(np.argmin(np.linalg.norm(pos[nodes] - c, axis=1)))]
        if np.linalg.norm(pos[k] - c) > 1e-9:
            raise RuntimeError("no mesh node at the face centre")
        return k

    sensors = [mbs.AddSensor(ei.SensorSuperElement(bodyNumber=bodies[b], meshNodeNumber=centre_node(tip, tip_c),
                                                   outputVariableType=exu.OutputVariableType.Position,
                                                   storeInternal=True, writeToFile=False))
               for b in (0, 1)]
    mbs.Assemble()

    s = exu.SimulationSettings()
    n_steps = int(round(seconds / step))
    s.timeIntegration.numberOfSteps = n_steps
    s.timeIntegration.endTime = seconds
    # rho_inf = 1 (no numerical damping) drifts into Newton failures and step cuts after ~7 s
    # (index-3 joints on a stiff FFRF body); 0.9 runs through, and halving the step changes the
    # result by < 4e-5 of the swing
    s.timeIntegration.generalizedAlpha.spectralRadius = spectral_radius
    s.timeIntegration.newton.useModifiedNewton = modified_newton  # reuse Jacobian: faster, same result
    s.timeIntegration.verboseMode = 1 if verbose else 0
    # tighter than the default 1e-8 stagnates near 4e-9 (round-off with K ~ 1e11) and makes the
    # solver cut the step size to 6e-5 s for the rest of the run
    s.timeIntegration.newton.relativeTolerance = 1e-8
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.5 * step  # record every step; resampled below
    s.show.statistics = verbose
    mbs.SolveDynamic(s)

    data = [mbs.GetSensorStoredData(k) for k in sensors]
    t_out = np.arange(int(round(seconds / SAMPLE)) + 1) * SAMPLE
    out = np.empty((len(t_out), 4))
    for j, d in enumerate(data):
        # sensors are written at the step times; pick the rows at every SAMPLE (step divides it)
        idx = np.searchsorted(d[:, 0], t_out - 0.25 * step)
        if idx.max() >= len(d) or np.abs(d[idx, 0] - t_out).max() > 1e-9:
            raise RuntimeError("sensor times do not hit every ms (step must divide 1 ms)")
        out[:, 2 * j] = d[idx, 1]
        out[:, 2 * j + 1] = d[idx, 3]
    return t_out, out
