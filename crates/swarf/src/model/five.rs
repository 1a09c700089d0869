//! A 5-axis pocket (paper 2 §2, Elber, Cohen, Drake): the region between a floor surface S(u, v)
//! and a top surface T(u, v) over the unit square, closed by walls along some sides of the
//! square and open along the others, with the tool (flat, bull-nose, ball or tapered, its shank
//! and holder), the rule the tool axis follows and the machine that tilts the table. The
//! geometry's conventions (which side is which, the ruled default wall, the field V = T − S)
//! are those of the case format in `docs/five.md`.

use crate::geom::nurbs::{NurbsSurface, SurfacePoint};
use glam::{DVec2, DVec3};

/// A side of the parameter square.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// u = 0.
    U0 = 0,
    /// u = 1.
    U1 = 1,
    /// v = 0.
    V0 = 2,
    /// v = 1.
    V1 = 3,
}

impl Side {
    /// The four sides, in the order of [`FiveJob::boundaries`].
    pub const ALL: [Side; 4] = [Side::U0, Side::U1, Side::V0, Side::V1];

    /// The point (u, v) of the side at `s` in [0, 1], s running with the floor's own
    /// parameter along it (u along v0 and v1, v along u0 and u1).
    pub fn at(self, s: f64) -> DVec2 {
        match self {
            Side::U0 => DVec2::new(0.0, s),
            Side::U1 => DVec2::new(1.0, s),
            Side::V0 => DVec2::new(s, 0.0),
            Side::V1 => DVec2::new(s, 1.0),
        }
    }

    /// The floor's parameter direction from this side into the pocket at the floor point
    /// `f` on it (S_u at u = 0, −S_u at u = 1, S_v at v = 0, −S_v at v = 1).
    pub fn inward(self, f: &SurfacePoint) -> DVec3 {
        match self {
            Side::U0 => f.su,
            Side::U1 => -f.su,
            Side::V0 => f.sv,
            Side::V1 => -f.sv,
        }
    }

    /// The side across the domain from this one.
    pub fn opposite(self) -> Side {
        match self {
            Side::U0 => Side::U1,
            Side::U1 => Side::U0,
            Side::V0 => Side::V1,
            Side::V1 => Side::V0,
        }
    }

    /// The side's key in the case format.
    pub fn key(self) -> &'static str {
        match self {
            Side::U0 => "u0",
            Side::U1 => "u1",
            Side::V0 => "v0",
            Side::V1 => "v1",
        }
    }
}

/// What closes a side of the pocket.
#[derive(Debug, Clone, PartialEq)]
pub enum Boundary {
    /// Air: the tool may enter and leave here.
    Open,
    /// A wall: the ruled surface from the floor's edge to the top's, unless the case gives
    /// its own surface over (s, w) (s along the side, w from floor to top).
    Wall(Option<NurbsSurface>),
}

/// The shape of the cutter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CutterKind {
    /// An end mill (a bull-nose with a corner radius).
    Flat,
    /// A ball-nose mill.
    Ball,
    /// A tapered mill: a cone of half angle [`FiveTool::taper_deg`].
    Tapered,
}

/// The tool as a solid of revolution, z along the axis from the tip.
#[derive(Debug, Clone, PartialEq)]
pub struct FiveTool {
    /// Its kind.
    pub kind: CutterKind,
    /// Diameter at the tip end (a tapered tool's cone at z = 0, before the corner rounding).
    pub diameter: f64,
    /// Corner radius (a ball's is its radius).
    pub corner_radius: f64,
    /// The cone's half angle, degrees (0 but for a tapered tool).
    pub taper_deg: f64,
    /// The cutting part: z from 0 to this.
    pub flute_length: f64,
    /// The shank's diameter, from the flutes to [`FiveTool::length`].
    pub shank_diameter: f64,
    /// Stick-out from the tip to the holder.
    pub length: f64,
    /// The holder above the stick-out: (diameter, length).
    pub holder: Option<(f64, f64)>,
}

impl FiveTool {
    /// The cutter's radius at height `z` above the tip (on the flutes).
    pub fn radius_at(&self, z: f64) -> f64 {
        let r = 0.5 * self.diameter;
        let q = self.taper_deg.to_radians();
        let rc = self.corner_radius;
        if z >= rc * (1.0 - q.sin()) {
            return r + z * q.tan();
        }
        // on the corner arc, centre (rho_c, rc)
        let rho_c = r + rc * q.tan() - rc / q.cos();
        let dz = rc - z.max(0.0);
        rho_c + (rc * rc - dz * dz).max(0.0).sqrt()
    }
}

/// The rule the tool axis follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisRule {
    /// V = (T − S) / |T − S|.
    Field,
    /// The floor's normal.
    Normal,
}

/// A table-tilting machine (LinuxCNC's `xyzac-trt` kinematics) and its rotary limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// The kinematics' name (`xyzac-trt`).
    pub kinematics: String,
    /// The rotation point, x.
    pub x_rot_point: f64,
    /// The rotation point, y.
    pub y_rot_point: f64,
    /// The rotation point, z.
    pub z_rot_point: f64,
    /// The offset between the A and C axes along y.
    pub y_offset: f64,
    /// The offset between the A and C axes along z.
    pub z_offset: f64,
    /// The tool length offset.
    pub tool_offset: f64,
    /// The least A, degrees.
    pub a_min: f64,
    /// The greatest A, degrees.
    pub a_max: f64,
}

impl Default for Machine {
    fn default() -> Self {
        Machine {
            kinematics: "xyzac-trt".into(),
            x_rot_point: 0.0,
            y_rot_point: 0.0,
            z_rot_point: 0.0,
            y_offset: 0.0,
            z_offset: -50.0,
            tool_offset: 0.0,
            a_min: -120.0,
            a_max: 120.0,
        }
    }
}

/// A 5-axis pocketing job.
#[derive(Debug, Clone, PartialEq)]
pub struct FiveJob {
    /// Its name (the file's stem).
    pub name: String,
    /// The floor S(u, v) over the unit square.
    pub floor: NurbsSurface,
    /// The top T(u, v), over the same square.
    pub top: NurbsSurface,
    /// The sides u0, u1, v0, v1 ([`Side::ALL`]).
    pub boundaries: [Boundary; 4],
    /// The tool.
    pub tool: FiveTool,
    /// The rule of the tool axis.
    pub axis: AxisRule,
    /// The greatest distance between neighbouring passes on the floor, mm (the paper's bound
    /// on the Hausdorff distance).
    pub stepover: f64,
    /// The scallop height below which the floor counts as covered, mm.
    pub scallop_tol: f64,
    /// Added to the wall band (where the floor is not judged for coverage), mm.
    pub wall_band_margin: f64,
    /// Links and retracts go this far above the top along the axis, mm.
    pub clearance: f64,
    /// Cutting feed, mm/min.
    pub feed: f64,
    /// Rapid rate, mm/min.
    pub rapid_rate: f64,
    /// The machine.
    pub machine: Machine,
}

impl FiveJob {
    /// The boundary of `side`.
    pub fn boundary(&self, side: Side) -> &Boundary {
        // (the sides are numbered in the order of `Side::ALL`)
        &self.boundaries[side as usize]
    }

    /// The floor's unit normal at (u, v), turned towards the top (zero where the floor is
    /// degenerate).
    pub fn floor_normal(&self, u: f64, v: f64) -> DVec3 {
        let n = self.floor.eval(u, v).normal();
        let up = self.top.eval(u, v).p - self.floor.eval(u, v).p;
        if n.dot(up) < 0.0 { -n } else { n }
    }

    /// The direction the tool axis follows at (u, v) before tilting for the walls: the field
    /// V = (T − S) / |T − S|, or the floor's normal ([`AxisRule`]); the normal where T meets S.
    pub fn axis_field(&self, u: f64, v: f64) -> DVec3 {
        match self.axis {
            AxisRule::Normal => self.floor_normal(u, v),
            AxisRule::Field => {
                let d = self.top.eval(u, v).p - self.floor.eval(u, v).p;
                if d.length() > 1e-12 { d.normalize() } else { self.floor_normal(u, v) }
            }
        }
    }

    /// The wall of `side` at (s, w): its own surface, or the ruled surface
    /// `(1 − w) S(b(s)) + w T(b(s))` from the floor's edge (w = 0) to the top's (w = 1); `None`
    /// for an open side.
    pub fn wall_point(&self, side: Side, s: f64, w: f64) -> Option<DVec3> {
        match self.boundary(side) {
            Boundary::Open => None,
            Boundary::Wall(Some(surface)) => Some(surface.eval(s, w).p),
            Boundary::Wall(None) => {
                let b = side.at(s);
                Some(self.floor.eval(b.x, b.y).p.lerp(self.top.eval(b.x, b.y).p, w))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cutter_profile() {
        let flat = FiveTool {
            kind: CutterKind::Flat,
            diameter: 5.0,
            corner_radius: 0.5,
            taper_deg: 0.0,
            flute_length: 20.0,
            shank_diameter: 5.0,
            length: 20.0,
            holder: None,
        };
        // the flat bottom is 2 mm, the corner reaches 2.5 at z = 0.5
        assert!((flat.radius_at(0.0) - 2.0).abs() < 1e-12);
        assert!((flat.radius_at(0.5) - 2.5).abs() < 1e-12);
        assert!((flat.radius_at(10.0) - 2.5).abs() < 1e-12);
        let tapered =
            FiveTool { kind: CutterKind::Tapered, diameter: 4.0, corner_radius: 0.25, taper_deg: 3.0, ..flat };
        let q = 3f64.to_radians();
        // on the cone, and continuous where the corner meets it
        assert!((tapered.radius_at(10.0) - (2.0 + 10.0 * q.tan())).abs() < 1e-12);
        let zt = 0.25 * (1.0 - q.sin());
        assert!((tapered.radius_at(zt - 1e-9) - tapered.radius_at(zt)).abs() < 1e-6);
    }
}
