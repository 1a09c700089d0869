//! GRBL 1.1: no tool changer (`M6` and `G43 H` are not accepted), so the tool is named in a
//! comment for the operator; no `G64`; program end `M2`.

use super::Dialect;

/// The GRBL dialect.
pub struct Grbl;

impl Dialect for Grbl {
    fn name(&self) -> &'static str {
        "grbl"
    }
    fn start_block(&self) -> Vec<String> {
        vec!["(start: metric, absolute, XY plane, feed per minute)".into(), "G21 G90 G17 G94".into()]
    }
    fn tool_change(&self, t: u32, d: f64) -> Vec<String> {
        vec![format!("(this program expects tool T{t}, a D{} flat end mill, fitted and zeroed)", super::num(d, 3))]
    }
    fn end_block(&self) -> Vec<String> {
        vec!["M2".into()]
    }
}
