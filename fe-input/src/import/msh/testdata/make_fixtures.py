"""Regenerates the small Gmsh MSH 4.1 test meshes of the .msh importer.

Each mesh is written twice from the same in-memory Gmsh model: as ASCII
(`<name>.msh`) and as binary (`<name>.bin.msh`), so the importer tests can
check that both give the same ImportedMesh.

    /tmp/gmsh-venv/bin/python make_fixtures.py      (Gmsh 4.15.2, PyPI wheel)

Run it in this directory.
"""

import gmsh


def save(name):
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    for binary, suffix in ((0, ".msh"), (1, ".bin.msh")):
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(name + suffix)


def extruded_block(nx, order, incomplete):
    """2 x 1 x 1 block of nx x 1 x 1 hexahedra (built-in kernel, extruded)."""
    p = gmsh.model.geo.addPoint(0, 0, 0)
    line = gmsh.model.geo.extrude([(0, p)], 2, 0, 0, [nx], recombine=True)[1]
    surf = gmsh.model.geo.extrude([line], 0, 1, 0, [1], recombine=True)[1]
    vol = gmsh.model.geo.extrude([surf], 0, 0, 1, [1], recombine=True)[1]
    gmsh.model.geo.synchronize()
    gmsh.model.addPhysicalGroup(3, [vol[1]], 1, "block")
    gmsh.model.addPhysicalGroup(2, [surf[1]], 2, "bottom")  # z = 0
    gmsh.model.mesh.generate(3)
    if order > 1:
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", incomplete)
        gmsh.model.mesh.setOrder(order)


def hex8():
    gmsh.model.add("hex8")
    extruded_block(2, 1, 0)
    # Parametric coordinates on curve and surface nodes (u / u v per node).
    gmsh.option.setNumber("Mesh.SaveParametric", 1)
    save("hex8")
    gmsh.option.setNumber("Mesh.SaveParametric", 0)


def hex20():
    gmsh.model.add("hex20")
    extruded_block(2, 2, 1)
    save("hex20")


def box_tets(name, order):
    """Unit cube of tetrahedra (OpenCASCADE box, coarse)."""
    gmsh.model.add(name)
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1, 1)
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), 1.0)
    x0 = gmsh.model.getEntitiesInBoundingBox(-0.1, -0.1, -0.1, 0.1, 1.1, 1.1, 2)
    x1 = gmsh.model.getEntitiesInBoundingBox(0.9, -0.1, -0.1, 1.1, 1.1, 1.1, 2)
    c = gmsh.model.getEntitiesInBoundingBox(0.9, -0.1, -0.1, 1.1, 0.1, 1.1, 1)
    gmsh.model.addPhysicalGroup(3, [1], 1, "body")
    gmsh.model.addPhysicalGroup(2, [t for _, t in x0], 2, "fixed")
    # Unnamed groups sharing tag 3 in two dimensions: PHYSICAL_2D_3 / _1D_3.
    gmsh.model.addPhysicalGroup(2, [t for _, t in x1], 3)
    gmsh.model.addPhysicalGroup(1, [t for _, t in c], 3)
    gmsh.model.mesh.generate(3)
    if order > 1:
        gmsh.model.mesh.setOrder(order)
    save(name)


gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
hex8()
hex20()
box_tets("tet4", 1)
box_tets("tet10", 2)
gmsh.finalize()
