// Two unit cubes of 4^3 hex8 cells, one above the other with a gap of 0.1: contact tests.
// gmsh -3 -format msh41 two_blocks.geo -o two_blocks.msh
SetFactory("Built-in");
n = 4;
For k In {0:1}
  z0 = k * 1.1;
  p = newp;
  Point(p) = {0, 0, z0}; Point(p+1) = {1, 0, z0}; Point(p+2) = {1, 1, z0}; Point(p+3) = {0, 1, z0};
  l = newl;
  Line(l) = {p, p+1}; Line(l+1) = {p+1, p+2}; Line(l+2) = {p+2, p+3}; Line(l+3) = {p+3, p};
  c = newll; Curve Loop(c) = {l, l+1, l+2, l+3};
  s = news; Plane Surface(s) = {c};
  Transfinite Curve{l, l+1, l+2, l+3} = n + 1;
  Transfinite Surface{s}; Recombine Surface{s};
  out[] = Extrude {0, 0, 1} { Surface{s}; Layers{n}; Recombine; };
  vol[k] = out[1];
  bot[k] = s;
  top[k] = out[0];
EndFor
Physical Volume("lower") = {vol[0]};
Physical Volume("upper") = {vol[1]};
Physical Surface("bottom") = {bot[0]};
Physical Surface("top") = {top[1]};
