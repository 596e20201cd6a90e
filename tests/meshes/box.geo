// A unit cube of tetrahedra with named physical groups, for the mesh-reader tests.
// gmsh -3 box.geo -format msh41 -o box_v41.msh (and -bin, and -format msh22)
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.CharacteristicLengthMax = 0.3;
Physical Volume("body") = {1};
Physical Surface("bottom") = {5};
Physical Surface("top") = {6};
Physical Surface("sides") = {1, 2, 3, 4};
Physical Curve("edge") = {1};
Physical Point("corner") = {1};
