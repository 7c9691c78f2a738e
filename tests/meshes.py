"""Structured meshes of a box in every supported CalculiX element type, written as Abaqus/CalculiX
decks by this test code (not by the builder), so the builder's importer and CalculiX read the very
same text.

Hexahedra: C3D8 (8 nodes), C3D20 and C3D20R (20 nodes). Tetrahedra: each hex cell split into six
tetrahedra around its main diagonal (Kuhn), which is conforming across cells; C3D4 (4 nodes) and
C3D10 (10 nodes, midside nodes at the edge midpoints). Quadratic meshes live on the lattice of
half-cells, so every midside node is shared by the elements around its edge.

Node order (CalculiX manual, section 6.2): C3D8 corners 1-4 on the bottom face counter-clockwise
seen from outside... i.e. (0,0,0) (1,0,0) (1,1,0) (0,1,0) then the top face; C3D20 adds the
midsides of edges 1-2, 2-3, 3-4, 4-1, 5-6, 6-7, 7-8, 8-5, 1-5, 2-6, 3-7, 4-8. C3D4 corners with
(2-1) x (3-1) pointing towards 4; C3D10 adds the midsides of 1-2, 2-3, 3-1, 1-4, 2-4, 3-4.
"""

from __future__ import annotations

import itertools

import numpy as np

HEX_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
HEX20_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]
TET10_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]
QUADRATIC = {"C3D20", "C3D20R", "C3D10"}
TETS = {"C3D4", "C3D10"}


def kuhn_tets():
    """The six tetrahedra of the unit cube sharing its diagonal (0,0,0)-(1,1,1), as corner triples."""
    tets = []
    for perm in itertools.permutations(range(3)):
        path = [np.zeros(3, int)]
        for axis in perm:
            step = path[-1].copy()
            step[axis] = 1
            path.append(step)
        tets.append([tuple(p) for p in path])
    return tets


class BoxMesh:
    """A structured mesh of [0, lx] x [0, ly] x [0, lz] with n = (nx, ny, nz) cells.

    `distort` moves every node by a smooth map (keeps straight edges straight for linear maps
    only, so it is a shear, which keeps midside nodes at midpoints)."""

    def __init__(self, etype: str, size, cells, shear=0.0):
        self.etype = etype.upper()
        self.size = np.asarray(size, float)
        self.cells = tuple(int(c) for c in cells)
        # quadratic elements sit on the half-cell lattice
        self.refine = 2 if self.etype in QUADRATIC else 1
        r = self.refine
        dims = [r * c + 1 for c in self.cells]
        self.ids = {}
        self.coords = []
        for k in range(dims[2]):
            for j in range(dims[1]):
                for i in range(dims[0]):
                    x = np.array([i / (dims[0] - 1), j / (dims[1] - 1), k / (dims[2] - 1)]) * self.size
                    x[0] += shear * x[2]  # a linear shear: elements are not rectangular
                    self.ids[(i, j, k)] = len(self.coords) + 1
                    self.coords.append(x)
        self.elements = []
        for cz in range(self.cells[2]):
            for cy in range(self.cells[1]):
                for cx in range(self.cells[0]):
                    self.elements += self._cell_elements((cx, cy, cz))
        used = {n for e in self.elements for n in e}
        # tet meshes on the half lattice use every point; hex20 leaves face and cell centres unused
        self.used = sorted(used)

    def _node(self, cell, corner2):
        """Node id at lattice offset `corner2` (in half-cells when quadratic) of `cell`."""
        r = self.refine
        return self.ids[tuple(r * c + o for c, o in zip(cell, corner2))]

    def _cell_elements(self, cell):
        r = self.refine
        if self.etype in TETS:
            out = []
            for tet in kuhn_tets():
                corners = [np.array(t) for t in tet]
                # orientation: (2-1) x (3-1) . (4-1) > 0
                if np.dot(np.cross(corners[1] - corners[0], corners[2] - corners[0]), corners[3] - corners[0]) < 0:
                    corners[1], corners[2] = corners[2], corners[1]
                nodes = [self._node(cell, tuple(r * c)) for c in corners]
                if self.etype == "C3D10":
                    nodes += [self._node(cell, tuple(corners[a] + corners[b])) for a, b in TET10_EDGES]
                out.append(nodes)
            return out
        corners = [np.array(c) for c in HEX_CORNERS]
        nodes = [self._node(cell, tuple(r * c)) for c in corners]
        if self.etype in ("C3D20", "C3D20R"):
            nodes += [self._node(cell, tuple(corners[a] + corners[b])) for a, b in HEX20_EDGES]
        return [nodes]

    def nodes_where(self, predicate) -> list[int]:
        return [n for n in self.used if predicate(self.coords[n - 1])]

    def deck(self, sets: dict, material=None, elset="SOLID") -> str:
        """The deck: used nodes, elements (in set `elset`), node sets {name: [ids]} and optionally
        a material (E, nu, rho) with its solid section."""
        lines = ["** structured test mesh written by tests/meshes.py", "*NODE, NSET=NALL"]
        for n in self.used:
            x = self.coords[n - 1]
            lines.append(f"{n}, {float(x[0])!r}, {float(x[1])!r}, {float(x[2])!r}")
        lines.append(f"*ELEMENT, TYPE={self.etype}, ELSET={elset}")
        for e, nodes in enumerate(self.elements, start=1):
            ids = [str(n) for n in nodes]
            # continuation: at most 16 entries per line
            head, tail = ids[:15], ids[15:]
            lines.append(f"{e}, " + ", ".join(head) + ("," if tail else ""))
            if tail:
                lines.append(", ".join(tail))
        for name, ids in sets.items():
            lines.append(f"*NSET, NSET={name}")
            for k in range(0, len(ids), 10):
                lines.append(", ".join(str(i) for i in ids[k:k + 10]))
        if material is not None:
            e, nu, rho = material
            lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", f"{e!r}, {nu!r}", "*DENSITY", f"{rho!r}",
                      f"*SOLID SECTION, ELSET={elset}, MATERIAL=STEEL"]
        return "\n".join(lines) + "\n"

    @property
    def n_dofs(self) -> int:
        return 3 * len(self.used)
