// An arm-like body for Sinew's bone-driven demo (inputs/arm.xml): an upper arm and a forearm joined at
// a rounded elbow, with two bones as holes whose surfaces are the bones' regions.
//   x: shoulder (x = 0) to wrist (x = 0.56); the elbow at x = 0.30.
//   humerus: x 0.000 .. 0.265, radius 0.014; forearm bone: x 0.335 .. 0.560, radius 0.011.
// Physical groups: volume "flesh"; surfaces "humerus", "forearm bone", "shoulder" (the x = 0 cap),
// "wrist" (the x = 0.56 cap), "skin".
// Regenerate (Gmsh 4.8): gmsh -3 arm.geo -format msh41 -bin -o arm.msh
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
humerus_s() = Surface In BoundingBox{-eps, -0.015, -0.015, 0.265 + eps, 0.015, 0.015};
radius_s() = Surface In BoundingBox{0.335 - eps, -0.012, -0.012, 0.56 + eps, 0.012, 0.012};
shoulder_s() = Surface In BoundingBox{-eps, -0.1, -0.1, eps, 0.1, 0.1};
wrist_s() = Surface In BoundingBox{0.56 - eps, -0.1, -0.1, 0.56 + eps, 0.1, 0.1};
shoulder_s() -= humerus_s();
wrist_s() -= radius_s();
all_s() = Boundary{ Volume{flesh()}; };
skin_s() = all_s();
skin_s() -= humerus_s();
skin_s() -= radius_s();
skin_s() -= shoulder_s();
skin_s() -= wrist_s();

Physical Volume("flesh") = {flesh()};
Physical Surface("humerus") = {humerus_s()};
Physical Surface("forearm bone") = {radius_s()};
Physical Surface("shoulder") = {shoulder_s()};
Physical Surface("wrist") = {wrist_s()};
Physical Surface("skin") = {skin_s()};
