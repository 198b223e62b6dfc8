// Name plaque, 120 x 100 mm, like the thesis's test sign: a plate with a
// rounded-over (curved) border, a raised half-round bead inset from the
// edge, and raised lettering with vertical walls.
// Rebuild: openscad -o plaque.stl plaque.scad   (binary STL via export below)
W = 120; H = 100;      // outline
T = 8;                 // plate thickness
R_edge = 5;            // round-over radius of the curved border
bead_inset = 9;        // bead centre line from the outline
bead_r = 2;            // bead radius (half-round, sits on the top face)
text_h = 2.5;          // raised lettering height
$fn = 128;

module corner_puck() {
  // A round-over corner: cylinder with a quarter-torus top edge.
  rotate_extrude() union() {
    square([R_edge, T - R_edge]);
    translate([0, T - R_edge]) square([R_edge, R_edge]);
    translate([R_edge, T - R_edge]) intersection() {
      circle(r = R_edge);
      square([R_edge, R_edge]);
    }
    square([2 * R_edge, T - R_edge]);
  }
}

module plate() {
  hull() for (x = [2 * R_edge, W - 2 * R_edge], y = [2 * R_edge, H - 2 * R_edge])
    translate([x, y, 0]) corner_puck();
}

module bead() {
  x0 = bead_inset; y0 = bead_inset; x1 = W - bead_inset; y1 = H - bead_inset;
  rc = 8;  // corner radius of the bead's path
  intersection() {
    translate([0, 0, T]) cube([W, H, bead_r + 1]);
    translate([0, 0, T]) union() {
      for (y = [y0, y1]) translate([x0 + rc, y, 0]) rotate([0, 90, 0]) cylinder(r = bead_r, h = x1 - x0 - 2 * rc);
      for (x = [x0, x1]) translate([x, y0 + rc, 0]) rotate([-90, 0, 0]) cylinder(r = bead_r, h = y1 - y0 - 2 * rc);
      for (c = [[x0 + rc, y0 + rc, 180], [x1 - rc, y0 + rc, 270], [x1 - rc, y1 - rc, 0], [x0 + rc, y1 - rc, 90]])
        translate([c[0], c[1], 0]) rotate([0, 0, c[2]])
          rotate_extrude(angle = 90) translate([rc, 0]) circle(r = bead_r);
    }
  }
}

module lettering() {
  translate([W / 2, 60, T - 0.01]) linear_extrude(height = text_h + 0.01)
    text("CNC", size = 22, font = "DejaVu Sans:style=Bold", halign = "center", valign = "center");
  translate([W / 2, 30, T - 0.01]) linear_extrude(height = text_h + 0.01)
    text("Stream", size = 16, font = "DejaVu Serif:style=Bold", halign = "center", valign = "center");
}

union() {
  plate();
  bead();
  lettering();
}
