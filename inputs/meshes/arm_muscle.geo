// The arm of arm.geo with a biceps as a body of its own (inputs/arm_muscle.xml): the muscle (a belly and
// two tendons down to the bones) and the fat/skin around it are meshed apart, with no shared nodes; the
// scene attaches them (sliding between muscle and fat, fixed where the tendons meet the bones).
//   x: shoulder (x = 0) to wrist (x = 0.56); the elbow at x = 0.30.
//   humerus: x 0.000 .. 0.265, radius 0.014; forearm bone: x 0.335 .. 0.560, radius 0.011.
//   belly: centre (0.15, 0, 0.034), semi-axes 0.10 (along the arm), 0.026, 0.014;
//   origin tendon: radius 0.006, x = 0.08, from the humerus up into the belly;
//   insertion tendon: radius 0.006, out of the belly along its axis, over the elbow to x = 0.37, down
//   onto the forearm bone.
// Physical groups: volumes "fat", "biceps"; surfaces "humerus", "forearm bone" (the fat's bone cavities),
// "shoulder", "wrist" (the caps), "skin", "fat cavity" (the fat's surface around the muscle), "biceps origin", "biceps insertion" (the tendons' ends on the
// bones), "biceps belly" (the belly's surface), "biceps tendons" (the rest of the muscle's boundary).
// Regenerate (Gmsh 4.8): gmsh -3 arm_muscle.geo -format msh41 -bin -o arm_muscle.msh
SetFactory("OpenCASCADE");
Mesh.CharacteristicLengthMax = 0.012;
Mesh.CharacteristicLengthMin = 0.005;
Mesh.Optimize = 1;

upper = newv; Cylinder(upper) = {0, 0, 0, 0.30, 0, 0, 0.050};
fore = newv; Cone(fore) = {0.30, 0, 0, 0.26, 0, 0, 0.044, 0.034};
elbow = newv; Sphere(elbow) = {0.30, 0, 0, 0.049};
bulge = newv; Sphere(bulge) = {0.15, 0, 0.012, 0.050};
Dilate {{0.15, 0, 0.012}, {1.9, 0.95, 1.0}} { Volume{bulge}; }
body() = BooleanUnion{ Volume{upper}; Delete; }{ Volume{fore, elbow, bulge}; Delete; };
clip = newv; Box(clip) = {0, -1, -1, 0.56, 2, 2};
body() = BooleanIntersection{ Volume{body()}; Delete; }{ Volume{clip}; Delete; };

belly = newv; Sphere(belly) = {0.15, 0, 0.034, 0.1};
// Turned first: dilated with its poles along y, the sphere's seam makes surfaces Gmsh meshes badly.
Rotate {{0, 0, 1}, {0.15, 0, 0.034}, Pi/2} { Volume{belly}; }
Dilate {{0.15, 0, 0.034}, {1.0, 0.26, 0.14}} { Volume{belly}; }
origin = newv; Cylinder(origin) = {0.08, 0, 0, 0, 0, 0.03, 0.006};
span = newv; Cylinder(span) = {0.20, 0, 0.034, 0.17, 0, -0.006, 0.006};
insertion = newv; Cylinder(insertion) = {0.37, 0, 0, 0, 0, 0.028, 0.006};
muscle() = BooleanUnion{ Volume{belly}; Delete; }{ Volume{origin, span, insertion}; Delete; };

humerus = newv; Cylinder(humerus) = {0, 0, 0, 0.265, 0, 0, 0.014};
radius = newv; Cylinder(radius) = {0.335, 0, 0, 0.225, 0, 0, 0.011};
bones() = BooleanUnion{ Volume{humerus}; Delete; }{ Volume{radius}; Delete; };
muscle() = BooleanDifference{ Volume{muscle()}; Delete; }{ Volume{bones()}; };
// The fat's cavity from a copy of the muscle: the two bodies then have surfaces of their own, meshed apart.
copy() = Translate {0, 0, 0} { Duplicata { Volume{muscle()}; } };
cavity() = BooleanUnion{ Volume{bones()}; Delete; }{ Volume{copy()}; Delete; };
fat() = BooleanDifference{ Volume{body()}; Delete; }{ Volume{cavity()}; Delete; };

eps = 1e-4;
// The fat's surfaces on the bones, and the muscle's.
humerus_all() = Surface In BoundingBox{-eps, -0.0141, -0.0141, 0.265 + eps, 0.0141, 0.0141};
radius_all() = Surface In BoundingBox{0.335 - eps, -0.0111, -0.0111, 0.56 + eps, 0.0111, 0.0111};
muscle_s() = Boundary{ Volume{muscle()}; };
fat_s() = Boundary{ Volume{fat()}; };
humerus_s() = humerus_all(); humerus_s() -= muscle_s();
radius_s() = radius_all(); radius_s() -= muscle_s();
origin_s() = humerus_all(); origin_s() -= fat_s();
insertion_s() = radius_all(); insertion_s() -= fat_s();
shoulder_s() = Surface In BoundingBox{-eps, -0.1, -0.1, eps, 0.1, 0.1};
wrist_s() = Surface In BoundingBox{0.56 - eps, -0.1, -0.1, 0.56 + eps, 0.1, 0.1};
shoulder_s() -= humerus_s();
wrist_s() -= radius_s();
skin_s() = CombinedBoundary{ Volume{fat()}; };
skin_s() -= humerus_s();
skin_s() -= radius_s();
skin_s() -= shoulder_s();
skin_s() -= wrist_s();
// The fat's cavity around the muscle: its surfaces within the muscle's bounding box that are not the bones'.
bb() = BoundingBox Volume{muscle()};
cavity_s() = Surface In BoundingBox{bb(0) - eps, bb(1) - eps, bb(2) - eps, bb(3) + eps, bb(4) + eps, bb(5) + eps};
cavity_s() -= muscle_s();
cavity_s() -= humerus_s();
cavity_s() -= radius_s();
skin_s() -= cavity_s();
// The belly's surface slides in the fat; the tendons' are tied to it. The belly is the one surface of
// the muscle longer than 0.2 (OpenCASCADE's boxes of curved surfaces are loose: no tighter test).
belly_s() = {};
For i In {0:#muscle_s() - 1}
  b() = BoundingBox Surface{muscle_s(i)};
  If (b(3) - b(0) > 0.2)
    belly_s() += muscle_s(i);
  EndIf
EndFor
tendon_s() = muscle_s();
tendon_s() -= origin_s();
tendon_s() -= insertion_s();
tendon_s() -= belly_s();

Physical Volume("fat") = {fat()};
Physical Volume("biceps") = {muscle()};
Physical Surface("humerus") = {humerus_s()};
Physical Surface("forearm bone") = {radius_s()};
Physical Surface("shoulder") = {shoulder_s()};
Physical Surface("wrist") = {wrist_s()};
Physical Surface("skin") = {skin_s()};
Physical Surface("fat cavity") = {cavity_s()};
Physical Surface("biceps origin") = {origin_s()};
Physical Surface("biceps insertion") = {insertion_s()};
Physical Surface("biceps belly") = {belly_s()};
Physical Surface("biceps tendons") = {tendon_s()};
