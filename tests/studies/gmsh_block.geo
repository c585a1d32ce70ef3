// A quarter of the alumina block of tests/studies/punched_block.toml (30 x 30 mm, 30 mm
// deep), meshed by Gmsh for tests/studies/gmsh_block.toml: x, y from the symmetry planes to
// the free sides, z from the floor up. In the plane, lines at x = 7 mm and y = 7 mm bound the
// square the DEM zone may take (1 mm elements inside it, one per particle spacing, so that
// any footprint's elements are whole particle cells), elements growing geometrically (ratio
// 1.25) to the sides; extruded in 15 layers, 1 mm over the top 8 mm, 1.75 mm below, then 5 mm
// over the bottom half (the tie hosts the particle rows in whichever elements hold them), all
// hexahedra.
// Physical groups: the volume "alumina" (the body, named as the case's material), the
// surface "floor" (the bottom face, named as the case's support).
// Regenerate: gmsh -3 -format msh41 gmsh_block.geo -o gmsh_block.msh
w = 7e-3;  a = 15e-3;  H = 30e-3;
xs[] = {0, w, a};
n[] = {8, 5};  // nodes along [0, w] and [w, a]
grow[] = {1.0, 1.25};
For i In {0:2}
  For j In {0:2}
    Point(10 * i + j + 1) = {xs[i], xs[j], 0};
  EndFor
EndFor
For i In {0:1}  // along x at y = xs[j]
  For j In {0:2}
    Line(100 + 10 * i + j) = {10 * i + j + 1, 10 * (i + 1) + j + 1};
    Transfinite Curve{100 + 10 * i + j} = n[i] Using Progression grow[i];
  EndFor
EndFor
For i In {0:2}  // along y at x = xs[i]
  For j In {0:1}
    Line(200 + 10 * i + j) = {10 * i + j + 1, 10 * i + j + 2};
    Transfinite Curve{200 + 10 * i + j} = n[j] Using Progression grow[j];
  EndFor
EndFor
For i In {0:1}
  For j In {0:1}
    Curve Loop(300 + 10 * i + j) = {100 + 10 * i + j, 200 + 10 * (i + 1) + j, -(100 + 10 * i + j + 1), -(200 + 10 * i + j)};
    Plane Surface(300 + 10 * i + j) = {300 + 10 * i + j};
    Transfinite Surface{300 + 10 * i + j};
    Recombine Surface{300 + 10 * i + j};
  EndFor
EndFor
body[] = Extrude {0, 0, H} { Surface{300, 301, 310, 311}; Layers{{3, 4, 8}, {0.5, 22 / 30, 1}}; Recombine; };
Physical Volume("alumina") = {body[1], body[7], body[13], body[19]};
Physical Surface("floor") = {300, 301, 310, 311};
