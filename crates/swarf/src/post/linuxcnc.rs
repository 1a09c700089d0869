//! LinuxCNC (rs274ngc): `G64 P` path blending within 0.01 mm, tool change with `M6` and the
//! length offset `G43 H`, program end `M2`.

use super::Dialect;

/// The LinuxCNC dialect.
pub struct LinuxCnc;

impl Dialect for LinuxCnc {
    fn name(&self) -> &'static str {
        "linuxcnc"
    }
    fn start_block(&self) -> Vec<String> {
        vec![
            "(start: metric, absolute, XY plane, feed per minute, cancel comp, offsets and cycles)".into(),
            "G21 G90 G17 G94 G40 G49 G80".into(),
            "G64 P0.01".into(),
        ]
    }
    fn tool_change(&self, t: u32, _d: f64) -> Vec<String> {
        vec![format!("T{t} M6"), format!("G43 H{t}")]
    }
    fn end_block(&self) -> Vec<String> {
        vec!["M2".into()]
    }
}
