// A half of the three-point-bend beam of tests/studies/three_point_bend.toml (span 40 mm,
// [0_2/90_2]s, plies 0.2 mm), meshed by Gmsh for tests/studies/gmsh_beam.toml: x from the
// mid-span symmetry plane to the support, y through the thickness. Lines at the ply runs'
// interfaces (y = 0.4, 1.2 mm) and at the DEM zone's edge (x = 6 mm), so that no element
// straddles either; transfinite quadrangles, 0.4 mm across the zone, growing geometrically
// (ratio 1.15) from the zone's edge to the support, two plies per element through the
// thickness. Physical groups: the surface "crossply" (the laminate, named as in the case file),
// the point "rollers" (the support under the beam's end, named as the case's support).
// Regenerate: gmsh -2 -format msh41 gmsh_beam.geo -o gmsh_beam.msh
w = 6e-3;  L = 20e-3;
xs[] = {0, w, L};
ys[] = {0, 0.4e-3, 1.2e-3, 1.6e-3};
along[] = {16, 13};  // nodes along x in [0, w] and [w, L]
grow[] = {1.0, 1.15};
through[] = {2, 3, 2};  // nodes through each ply run
For i In {0:2}
  For j In {0:3}
    Point(10 * i + j + 1) = {xs[i], ys[j], 0};
  EndFor
EndFor
For i In {0:1}  // along x at level j
  For j In {0:3}
    Line(100 + 10 * i + j) = {10 * i + j + 1, 10 * (i + 1) + j + 1};
    Transfinite Curve{100 + 10 * i + j} = along[i] Using Progression grow[i];
  EndFor
EndFor
For i In {0:2}  // through the thickness at column i
  For j In {0:2}
    Line(200 + 10 * i + j) = {10 * i + j + 1, 10 * i + j + 2};
    Transfinite Curve{200 + 10 * i + j} = through[j];
  EndFor
EndFor
s = 0;
For i In {0:1}
  For j In {0:2}
    Curve Loop(300 + 10 * i + j) = {100 + 10 * i + j, 200 + 10 * (i + 1) + j, -(100 + 10 * i + j + 1),
                                    -(200 + 10 * i + j)};
    Plane Surface(300 + 10 * i + j) = {300 + 10 * i + j};
    Transfinite Surface{300 + 10 * i + j};
    surfaces[s] = 300 + 10 * i + j;  s += 1;
  EndFor
EndFor
Recombine Surface{surfaces[]};
Physical Surface("crossply") = {surfaces[]};
Physical Point("rollers") = {21};
