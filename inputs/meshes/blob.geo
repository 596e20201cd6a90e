// A soft blob for the drop test (Smith et al. 2018, Fig. 11): an ellipsoid of semi-axes 0.15 x 0.1 x
// 0.08 m centred at (0, 0, 0.35), meshed with tetrahedra of size h:
//   gmsh -3 -setnumber h 0.02 -format msh41 -bin blob.geo -o blob.msh         (inputs/squash.xml, 3,217 tets)
//   gmsh -3 -setnumber h 0.03 -format msh41 -bin blob.geo -o blob_coarse.msh  (tests, 1,033 tets)
//   gmsh -3 -setnumber h 0.0038 ... (411,665 tets; perf/run.sh --drop: the paper's size)
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.025;
EndIf
Sphere(1) = {0, 0, 0, 1};
Dilate {{0, 0, 0}, {0.15, 0.1, 0.08}} { Volume{1}; }
Translate {0, 0, 0.35} { Volume{1}; }
Physical Volume("blob") = {1};
Mesh.CharacteristicLengthMin = h;
Mesh.CharacteristicLengthMax = h;
Mesh.Optimize = 1;
