// Angle bracket (SI units: metres), meshed with second-order tetrahedra.
//
// Regenerate bracket.msh and bracket.inp (both written by the Save commands
// at the end of this script, from one and the same mesh) with Gmsh 4.15.2
// (PyPI wheel; the output is reproduced byte for byte):
//
//   python3 -m venv /tmp/gmsh-venv && /tmp/gmsh-venv/bin/pip install gmsh==4.15.2
//   cd examples/bracket && /tmp/gmsh-venv/bin/python /tmp/gmsh-venv/bin/gmsh bracket.geo -
//
// The trailing `-` parses the script (which meshes and saves) and exits.
// `gmsh bracket.geo -` with any gmsh 4.15.2 binary on the PATH does the same;
// the pip wrapper script starts with `#!/usr/bin/env python`, hence the venv
// python above. Run it in this directory: the files are always written next
// to this script, but the .inp *Heading line repeats the path given to gmsh.
//
// Geometry: x along the base plate, y across the width, z up.
//   base plate    x in [0, 0.080], y in [0, 0.040], z in [0, 0.006]
//   upright plate x in [0, 0.006], y in [0, 0.040], z in [0, 0.060]
//   inner fillet  radius 0.004 along the concave edge x = z = 0.006
//   base hole     diameter 0.0085, axis through (0.055, 0.020, 0), direction +z
//   upright hole  diameter 0.0085, axis through (0, 0.020, 0.040), direction +x
// CAD volume = 0.080*0.040*0.006 + 0.006*0.040*0.054
//            + (1 - pi/4)*0.004^2*0.040 - 2*pi*0.00425^2*0.006
//            = 3.161641e-5 m^3.
//
// Physical groups: volume "BRACKET"; surfaces "BOLT_BASE" and "BOLT_ARM" (the
// cylindrical faces of the two holes). Midside nodes are placed on the CAD
// geometry (Gmsh default, Mesh.SecondOrderLinear = 0), i.e. the tet10 edges on
// the hole cylinders and on the fillet are curved; all other edges are
// straight with their midside node at the midpoint.

SetFactory("OpenCASCADE");

lc = 0.0055;      // global element size
lc_hole = 0.0025; // element size on the hole edges (about 11 segments per hole)

Box(1) = {0, 0, 0, 0.080, 0.040, 0.006};
Box(2) = {0, 0, 0, 0.006, 0.040, 0.060};
v() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; };

eps = 1e-6;
// The concave edge between the two plates.
c() = Curve In BoundingBox{0.006 - eps, -eps, 0.006 - eps, 0.006 + eps, 0.040 + eps, 0.006 + eps};
f() = Fillet{v(0)}{c(0)}{0.004};

r = 0.00425;
Cylinder(10) = {0.055, 0.020, -0.001, 0, 0, 0.008, r};
Cylinder(11) = {-0.001, 0.020, 0.040, 0.008, 0, 0, r};
b() = BooleanDifference{ Volume{f(0)}; Delete; }{ Volume{10, 11}; Delete; };

sb() = Surface In BoundingBox{0.055 - r - eps, 0.020 - r - eps, -eps, 0.055 + r + eps, 0.020 + r + eps, 0.006 + eps};
sa() = Surface In BoundingBox{-eps, 0.020 - r - eps, 0.040 - r - eps, 0.006 + eps, 0.020 + r + eps, 0.040 + r + eps};
If (#b() != 1 || #sb() != 1 || #sa() != 1)
  Error("unexpected topology: %g volumes, %g base hole faces, %g arm hole faces", #b(), #sb(), #sa());
EndIf

Physical Volume("BRACKET") = {b(0)};
Physical Surface("BOLT_BASE") = {sb()};
Physical Surface("BOLT_ARM") = {sa()};

Mesh.MeshSizeMin = 0.001;
Mesh.MeshSizeMax = lc;
MeshSize{ PointsOf{ Surface{sb(), sa()}; } } = lc_hole;
Mesh.ElementOrder = 2;

// Output: MSH 4.1 ASCII (nodes %.16g; tet10 elements plus the tri6 elements
// of the two hole faces, which only carry the physical groups).
// Abaqus .inp (nodes %.14g, same node and element ids as the .msh):
// SaveGroupsOfElements = -1000 writes the elements and element sets of
// dimension 3 only (*ELEMENT, TYPE=C3D10, ELSET=Volume1 and *ELSET BRACKET;
// the default would add CPS6 elements for the hole faces, which the
// fmu-builder importer rejects), SaveGroupsOfNodes = 1 a node set per
// physical group (*NSET BOLT_BASE, BOLT_ARM, BRACKET).
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.SaveGroupsOfElements = -1000;
Mesh.SaveGroupsOfNodes = 1;

Mesh 3;
Save "bracket.msh";
Save "bracket.inp";
