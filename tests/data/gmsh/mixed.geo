// Reference mesh for uvr's Gmsh reader tests: a hexahedral slab (extruded, recombined) under a tetrahedral
// box, with pyramids where tets meet the hexes' quads, and beside them a prism slab extruded from a
// triangulated square. Volume 1 x 1 x 1.1 + 1 x 1 x 0.4. The .msh files beside it were written by Debian 12's
// gmsh 4.8.4:
//   gmsh -3 mixed.geo -format msh22 [-bin] -o mixed_22_{ascii,binary}.msh
//   gmsh -3 mixed.geo -format msh41 [-bin] -o mixed_41_{ascii,binary}.msh
//   gmsh -3 mixed.geo -order 2 -format msh41 -o mixed_order2_41_ascii.msh
//   gmsh -3 mixed.geo -order 2 -format msh22 -bin -o mixed_order2_22_binary.msh
SetFactory("Built-in");
Point(1) = {0, 0, 0, 0.5}; Point(2) = {1, 0, 0, 0.5}; Point(3) = {1, 1, 0, 0.5}; Point(4) = {0, 1, 0, 0.5};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 2, 3, 4} = 3; Transfinite Surface{1}; Recombine Surface{1};
hex[] = Extrude {0, 0, 0.5} { Surface{1}; Layers{2}; Recombine; };
tet[] = Extrude {0, 0, 0.6} { Surface{hex[0]}; };
Point(101) = {2, 0, 0, 0.5}; Point(102) = {3, 0, 0, 0.5}; Point(103) = {3, 1, 0, 0.5}; Point(104) = {2, 1, 0, 0.5};
Line(101) = {101, 102}; Line(102) = {102, 103}; Line(103) = {103, 104}; Line(104) = {104, 101};
Curve Loop(101) = {101, 102, 103, 104}; Plane Surface(101) = {101};
prism[] = Extrude {0, 0, 0.4} { Surface{101}; Layers{2}; Recombine; };
Physical Volume("all") = {hex[1], tet[1], prism[1]};
