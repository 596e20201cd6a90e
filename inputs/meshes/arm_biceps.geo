// The arm of arm.geo with a biceps inside its flesh (inputs/arm_biceps.xml): an ellipsoid on the flexing
// side of the upper arm, fragmented with the flesh so that the two volumes share their interface nodes
// (welded: the muscle is a region of one body, not a body of its own).
//   biceps: centre (0.15, 0, 0.032), semi-axes 0.10 (along the arm), 0.028, 0.016; clear of the humerus
//   (z >= 0.016 > 0.014) and of the skin.
//   x: shoulder (x = 0) to wrist (x = 0.56); the elbow at x = 0.30.
//   humerus: x 0.000 .. 0.265, radius 0.014; forearm bone: x 0.335 .. 0.560, radius 0.011.
// Physical groups: volumes "flesh" and "biceps"; surfaces "humerus", "forearm bone", "shoulder" (the x = 0 cap),
// "wrist" (the x = 0.56 cap), "skin".
// Regenerate (Gmsh 4.8): gmsh -3 arm_biceps.geo -format msh41 -bin -o arm_biceps.msh
SetFactory("OpenCASCADE");
Mesh.CharacteristicLengthMax = 0.012;
Mesh.CharacteristicLengthMin = 0.006;
Mesh.Optimize = 1;

upper = newv; Cylinder(upper) = {0, 0, 0, 0.30, 0, 0, 0.050};
fore = newv; Cone(fore) = {0.30, 0, 0, 0.26, 0, 0, 0.044, 0.034};
elbow = newv; Sphere(elbow) = {0.30, 0, 0, 0.049};
// A biceps-like bulge on the upper arm's front (+z) side.
bulge = newv; Sphere(bulge) = {0.15, 0, 0.012, 0.050};
Dilate {{0.15, 0, 0.012}, {1.9, 0.95, 1.0}} { Volume{bulge}; }
body() = BooleanUnion{ Volume{upper}; Delete; }{ Volume{fore, elbow, bulge}; Delete; };
// Keep the bulge inside the arm's length.
clip = newv; Box(clip) = {0, -1, -1, 0.56, 2, 2};
body() = BooleanIntersection{ Volume{body()}; Delete; }{ Volume{clip}; Delete; };
humerus = newv; Cylinder(humerus) = {0, 0, 0, 0.265, 0, 0, 0.014};
radius = newv; Cylinder(radius) = {0.335, 0, 0, 0.225, 0, 0, 0.011};
flesh() = BooleanDifference{ Volume{body()}; Delete; }{ Volume{humerus, radius}; Delete; };
eps = 1e-4;
muscle = newv; Sphere(muscle) = {0.15, 0, 0.032, 0.1};
// Turned first: dilated with its poles along y, the sphere's seam meets the flesh in a surface Gmsh cannot mesh.
Rotate {{0, 0, 1}, {0.15, 0, 0.032}, Pi/2} { Volume{muscle}; }
Dilate {{0.15, 0, 0.032}, {1.0, 0.28, 0.16}} { Volume{muscle}; }
parts() = BooleanFragments{ Volume{flesh()}; Delete; }{ Volume{muscle}; Delete; };
biceps() = {muscle};  // inside the flesh, the fragment keeps its tag
flesh() = parts();
flesh() -= biceps();

eps = 1e-4;
humerus_s() = Surface In BoundingBox{-eps, -0.015, -0.015, 0.265 + eps, 0.015, 0.015};
radius_s() = Surface In BoundingBox{0.335 - eps, -0.012, -0.012, 0.56 + eps, 0.012, 0.012};
shoulder_s() = Surface In BoundingBox{-eps, -0.1, -0.1, eps, 0.1, 0.1};
wrist_s() = Surface In BoundingBox{0.56 - eps, -0.1, -0.1, 0.56 + eps, 0.1, 0.1};
shoulder_s() -= humerus_s();
wrist_s() -= radius_s();
all_s() = CombinedBoundary{ Volume{flesh(), biceps()}; };
skin_s() = all_s();
skin_s() -= humerus_s();
skin_s() -= radius_s();
skin_s() -= shoulder_s();
skin_s() -= wrist_s();

Physical Volume("flesh") = {flesh()};
Physical Volume("biceps") = {biceps()};
Physical Surface("humerus") = {humerus_s()};
Physical Surface("forearm bone") = {radius_s()};
Physical Surface("shoulder") = {shoulder_s()};
Physical Surface("wrist") = {wrist_s()};
Physical Surface("skin") = {skin_s()};
