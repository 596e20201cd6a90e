// The arm's skin as a closed triangle surface, for the voxelized demo (inputs/arm_voxel.xml): the
// body of arm.geo without the bone holes. Sinew fills it with hex8 cells (Mesh/Type voxelize).
// Regenerate (Gmsh 4.8): gmsh -2 arm_skin.geo -format stl -bin -o arm_skin.stl
SetFactory("OpenCASCADE");
Mesh.CharacteristicLengthMax = 0.012;
Mesh.CharacteristicLengthMin = 0.006;

upper = newv; Cylinder(upper) = {0, 0, 0, 0.30, 0, 0, 0.050};
fore = newv; Cone(fore) = {0.30, 0, 0, 0.26, 0, 0, 0.044, 0.034};
elbow = newv; Sphere(elbow) = {0.30, 0, 0, 0.049};
bulge = newv; Sphere(bulge) = {0.15, 0, 0.012, 0.050};
Dilate {{0.15, 0, 0.012}, {1.9, 0.95, 1.0}} { Volume{bulge}; }
body() = BooleanUnion{ Volume{upper}; Delete; }{ Volume{fore, elbow, bulge}; Delete; };
clip = newv; Box(clip) = {0, -1, -1, 0.56, 2, 2};
body() = BooleanIntersection{ Volume{body()}; Delete; }{ Volume{clip}; Delete; };
