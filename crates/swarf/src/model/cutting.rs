//! The cutting data jobs share: the tool and the width of cut.

use crate::error::{Error, Result};

/// A flat end mill.
#[derive(Debug, Clone, PartialEq)]
pub struct Tool {
    /// Diameter, mm.
    pub diameter: f64,
    /// Tool number written in the program (`T1`).
    pub number: u32,
    /// Number of flutes (for feeds per tooth in reports).
    pub flutes: u32,
}

impl Tool {
    /// A flat end mill of the given diameter, tool number 1.
    pub fn flat(diameter: f64) -> Tool {
        Tool { diameter, number: 1, flutes: 2 }
    }
    /// Radius, mm.
    pub fn radius(&self) -> f64 {
        self.diameter / 2.0
    }
}

/// How wide the cut is: a tool engagement angle or a radial stepover.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Width {
    /// Tool engagement angle in degrees, in (0, 180].
    EngagementDeg(f64),
    /// Radial stepover as a fraction of the diameter, in (0, 1].
    Stepover(f64),
}

impl Width {
    /// Stepover fraction of a straight cut with this width: `s = (1 - cos θ) / 2`, the inverse of
    /// paper 1 eq. 3, `θ = 90° + asin(2s − 1)`.
    pub fn stepover(self) -> f64 {
        match self {
            Width::Stepover(s) => s,
            Width::EngagementDeg(t) => (1.0 - t.to_radians().cos()) / 2.0,
        }
    }
    /// Engagement angle in degrees of a straight cut with this width (paper 1 eq. 3).
    pub fn engagement_deg(self) -> f64 {
        match self {
            Width::EngagementDeg(t) => t,
            Width::Stepover(s) => 90.0 + (2.0 * s - 1.0).clamp(-1.0, 1.0).asin().to_degrees(),
        }
    }
    /// Checks the range.
    pub fn validate(self, place: &str) -> Result<()> {
        match self {
            Width::Stepover(s) if !(s > 0.0 && s <= 1.0) => {
                Err(Error::param(place, format!("{s} is outside (0, 1] (a fraction of the tool diameter)")))
            }
            Width::EngagementDeg(t) if !(t > 0.0 && t <= 180.0) => {
                Err(Error::param(place, format!("{t}° is outside (0°, 180°]")))
            }
            _ => Ok(()),
        }
    }
}

/// Checks a tool's diameter and a width of cut (a 2.5D job's and a mesh job's alike).
pub(crate) fn check_tool_and_width(tool: &Tool, width: Width) -> Result<()> {
    let d = tool.diameter;
    if !(d.is_finite() && d > 0.0) {
        return Err(Error::param("tool diameter", format!("{d} mm: the tool diameter must be a positive number")));
    }
    width.validate(match width {
        Width::Stepover(_) => "stepover",
        Width::EngagementDeg(_) => "engagement",
    })
}
