// Two bodies, one on the other, meshed apart (no shared nodes, non-matching at the interface): attachment
// tests. lower: [0,1] x [0,1] x [0,0.5], 4 x 4 x 2 hex8; upper: [0.2,0.8] x [0.2,0.8] x [0.5,1], 3 x 3 x 3 hex8.
// gmsh -3 -format msh41 stacked_blocks.geo -o stacked_blocks.msh
SetFactory("Built-in");
lo[] = {0, 0.2};  hi[] = {1, 0.8};  zlo[] = {0, 0.5};  n[] = {4, 3};  nz[] = {2, 3};
For k In {0:1}
  p = newp;
  Point(p) = {lo[k], lo[k], zlo[k]}; Point(p+1) = {hi[k], lo[k], zlo[k]};
  Point(p+2) = {hi[k], hi[k], zlo[k]}; Point(p+3) = {lo[k], hi[k], zlo[k]};
  l = newl;
  Line(l) = {p, p+1}; Line(l+1) = {p+1, p+2}; Line(l+2) = {p+2, p+3}; Line(l+3) = {p+3, p};
  c = newll; Curve Loop(c) = {l, l+1, l+2, l+3};
  s = news; Plane Surface(s) = {c};
  Transfinite Curve{l, l+1, l+2, l+3} = n[k] + 1;
  Transfinite Surface{s}; Recombine Surface{s};
  out[] = Extrude {0, 0, 0.5} { Surface{s}; Layers{nz[k]}; Recombine; };
  vol[k] = out[1]; bot[k] = s; top[k] = out[0];
EndFor
Physical Volume("lower") = {vol[0]};
Physical Volume("upper") = {vol[1]};
Physical Surface("bottom") = {bot[0]};
Physical Surface("lower top") = {top[0]};
Physical Surface("upper bottom") = {bot[1]};
Physical Surface("top") = {top[1]};
