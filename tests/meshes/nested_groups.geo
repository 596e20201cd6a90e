// Two unit cubes side by side; "all" holds both, "tendon" the second: an element in two volume groups.
// gmsh -3 nested_groups.geo -format msh2 -o nested_groups_v22.msh; ... -format msh41 -o nested_groups_v41.msh
SetFactory("OpenCASCADE");
Box(1) = {0,0,0, 1,1,1};
Box(2) = {1,0,0, 1,1,1};
Coherence;
Physical Volume("all") = {1,2};
Physical Volume("tendon") = {2};
Physical Surface("left") = {1};
MeshSize{ PointsOf{ Volume{:}; } } = 0.5;
