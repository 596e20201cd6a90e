// A 1 x 1 x 2 box of 3 x 3 x 6 hexahedra (transfinite, recombined), two volume groups, for the
// mesh-reader tests. gmsh -3 hexbox.geo -format msh41 -o hexbox_v41.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
Coherence;
Transfinite Curve {:} = 4;
Transfinite Surface {:};
Recombine Surface {:};
Transfinite Volume {:};
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Surface("floor") = {5};
