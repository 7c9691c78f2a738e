"""CalculiX's stresses, read back for the stress-recovery tests.

Two references on the builder's mesh (deck from `fmu-builder --export-inp`):

- `frd_nodal_stresses`: CalculiX's own nodal stresses (`*EL FILE` S in the .frd): its
  integration-point stresses extrapolated to the nodes with its tables and averaged over the
  elements of each node. Its tables are the extrapolation matrices rounded to 3..5 decimals
  (C3D10: 1.92705, -0.30902; C3D8/C3D20R: 2.549, -0.683, 0.183, -0.04904; C3D20: 2.37499, ...),
  and the .frd carries 6 significant digits: agreement is bounded by that rounding.
- `el_print_stresses` + `nodal_from_points`: CalculiX's integration-point stresses (`*EL PRINT`
  S in the .dat, 7 significant digits), extrapolated here with the exact matrices (computed below
  with numpy from the shape functions, independently of the builder's Rust code) and averaged
  as CalculiX averages: the same definition without the tables' rounding.

Components are returned in the builder's order xx, yy, zz, xy, yz, zx.
"""

from __future__ import annotations

import numpy as np

import calculix as ccx

#: the 2x2x2 and 3x3x3 Gauss abscissae and the 4-point tetrahedron rule, in CalculiX's order
#: (gauss.f: xi runs fastest)
G2 = [-1 / np.sqrt(3), 1 / np.sqrt(3)]
G3 = [-np.sqrt(0.6), 0.0, np.sqrt(0.6)]
TET_A, TET_B = (5 - np.sqrt(5)) / 20, (5 + 3 * np.sqrt(5)) / 20
HEX20_NODES = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1), (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1),
               (0, -1, -1), (1, 0, -1), (0, 1, -1), (-1, 0, -1), (0, -1, 1), (1, 0, 1), (0, 1, 1), (-1, 0, 1),
               (-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
HEX20_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]
TET10_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


def _hex_points(g):
    return [(x, y, z) for z in g for y in g for x in g]


def _trilinear(p):
    return [0.125 * (1 + s[0] * p[0]) * (1 + s[1] * p[1]) * (1 + s[2] * p[2]) for s in HEX20_NODES[:8]]


def _serendipity(p):
    out = []
    for s in HEX20_NODES:
        if 0 not in s:
            f = [1 + s[i] * p[i] for i in range(3)]
            out.append(0.125 * f[0] * f[1] * f[2] * (sum(s[i] * p[i] for i in range(3)) - 2))
        else:
            a = s.index(0)
            b, c = (a + 1) % 3, (a + 2) % 3
            out.append(0.25 * (1 - p[a] ** 2) * (1 + s[b] * p[b]) * (1 + s[c] * p[c]))
    return out


def _tet_corners(p):
    return [1 - p[0] - p[1] - p[2], p[0], p[1], p[2]]


def _extrapolation(kind: str):
    """(matrix nodes_direct x points, midside corner pairs) for a CalculiX element type."""
    if kind == "C3D4":
        return np.ones((4, 1)), []
    if kind == "C3D10":
        pts = [(TET_A, TET_A, TET_A), (TET_B, TET_A, TET_A), (TET_A, TET_B, TET_A), (TET_A, TET_A, TET_B)]
        return np.linalg.inv(np.array([_tet_corners(p) for p in pts])), TET10_EDGES
    if kind in ("C3D8", "C3D20R"):
        inv = np.linalg.inv(np.array([_trilinear(p) for p in _hex_points(G2)]))
        return inv, (HEX20_EDGES if kind == "C3D20R" else [])
    if kind == "C3D20":
        a = np.array([_serendipity(p) for p in _hex_points(G3)])
        return np.linalg.solve(a.T @ a, a.T), []
    raise ValueError(f"no extrapolation for {kind}")


def elements(deck: str) -> dict[int, tuple[str, list[int]]]:
    """{element id: (type, node ids)} of every *ELEMENT block (continuation lines joined)."""
    out = {}
    for keyword, lines in ccx._blocks(deck):
        params = ccx._params(keyword)
        if params[""] != "*ELEMENT":
            continue
        kind = params["TYPE"].upper()
        tokens = [int(t) for line in lines for t in line.split(",") if t.strip()]
        per = {"C3D4": 4, "C3D10": 10, "C3D8": 8, "C3D20": 20, "C3D20R": 20}[kind] + 1
        assert len(tokens) % per == 0, f"{kind} block of {len(tokens)} numbers"
        for i in range(0, len(tokens), per):
            out[tokens[i]] = (kind, tokens[i + 1:i + per])
    return out


def el_print_stresses(dat: str) -> dict[int, np.ndarray]:
    """{element: array(points x 6)} from the .dat's `*EL PRINT` S blocks (last one wins)."""
    points: dict[int, dict[int, np.ndarray]] = {}
    inside = False
    for line in dat.splitlines():
        if line.strip().startswith("stresses (elem, integ.pnt."):
            inside, points = True, {}
            continue
        tokens = line.split()
        if inside and len(tokens) == 8 and tokens[0].isdigit():
            v = np.array([ccx._real(t) for t in tokens[2:]])
            # CalculiX: sxx syy szz sxy sxz syz
            points.setdefault(int(tokens[0]), {})[int(tokens[1])] = v[[0, 1, 2, 3, 5, 4]]
        elif inside and tokens:
            inside = False
    return {e: np.array([p[i] for i in sorted(p)]) for e, p in points.items()}


def frd_nodal_stresses(frd: str) -> dict[int, np.ndarray]:
    """{node: (sxx, syy, szz, sxy, syz, szx)} of the last STRESS block of a .frd file."""
    out: dict[int, np.ndarray] = {}
    inside = False
    for line in frd.splitlines():
        if line.startswith(" -4  STRESS"):
            inside, out = True, {}
            continue
        if inside and line.startswith(" -1"):
            values = [float(line[13 + 12 * i:25 + 12 * i]) for i in range(6)]
            out[int(line[3:13])] = np.array(values)
        elif inside and line.startswith(" -3"):
            inside = False
    return out


def nodal_from_points(deck: str, at_points: dict[int, np.ndarray], nodes: list[int]) -> dict[int, np.ndarray]:
    """Nodal stresses at `nodes`: every element's integration-point stresses extrapolated to
    its nodes with the exact matrices, averaged over the elements of the node."""
    wanted = set(nodes)
    sums = {n: np.zeros(6) for n in nodes}
    counts = {n: 0 for n in nodes}
    tables = {}
    for e, (kind, conn) in elements(deck).items():
        if wanted.isdisjoint(conn):
            continue
        if kind not in tables:
            tables[kind] = _extrapolation(kind)
        matrix, midsides = tables[kind]
        s = at_points[e]
        assert s.shape == (matrix.shape[1], 6), f"element {e}: {s.shape} stresses for a {kind}"
        direct = matrix @ s
        at_nodes = list(direct) + [0.5 * (direct[a] + direct[b]) for a, b in midsides]
        assert len(at_nodes) == len(conn)
        for n, v in zip(conn, at_nodes):
            if n in wanted:
                sums[n] += v
                counts[n] += 1
    return {n: sums[n] / counts[n] for n in nodes}


def stress_step(*loads: str) -> str:
    """A `*STATIC` step with the loads, writing the nodal stresses to the .frd and printing the
    integration-point stresses of every element into the .dat."""
    return "*STEP\n*STATIC\n" + "".join(loads) + "*EL FILE\nS\n*EL PRINT, ELSET=EALL\nS\n*END STEP\n"

