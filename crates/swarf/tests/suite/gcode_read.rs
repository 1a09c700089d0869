//! swarf's own programs read back by its G-code reader (`swarf::io::gcode`): through both
//! posts, the same cutting moves, end points and length as written. (Here, not beside the
//! reader: it needs the rough job, a layer above the readers.)

use std::path::Path;
use swarf::geom::DVec3;
use swarf::io::gcode::{ReadOptions, read};
use swarf::post::{self, Header, Post};
use swarf::{RoughOptions, rough};

#[test]
fn swarf_programs_read_back_as_written() {
    let job = swarf::example_job();
    let done = rough(&job, &RoughOptions { simulate: false, ..RoughOptions::DEFAULT }, &mut |_, _| {}).unwrap();
    let tp = &done.toolpath;
    for post in [Post::LinuxCnc, Post::Grbl] {
        let text = post::write(tp, post, &Header { lines: vec!["a test".into()], spindle_rpm: 12000.0 }).unwrap();
        let opts = ReadOptions { tool: tp.tool.clone(), clearance_z: None };
        let p = read(&text, Path::new("rt.ngc"), &opts).unwrap();
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        assert_eq!(p.toolpath.clearance_z, tp.clearance_z);
        let cuts: Vec<DVec3> = tp.moves.iter().filter(|m| !m.is_rapid()).map(|m| m.to).collect();
        // the read cutting moves by source line, each line's last end point
        let mut read_cuts: Vec<(u32, DVec3)> = Vec::new();
        for (m, &line) in p.toolpath.moves.iter().zip(&p.lines) {
            if m.is_rapid() {
                continue;
            }
            match read_cuts.last_mut() {
                Some((l, to)) if *l == line => *to = m.to,
                _ => read_cuts.push((line, m.to)),
            }
        }
        assert_eq!(read_cuts.len(), cuts.len(), "{post:?}");
        for (i, ((line, got), want)) in read_cuts.iter().zip(&cuts).enumerate() {
            assert!((*got - *want).length() < 1e-3, "{post:?}: cut {i} (line {line}) ends at {got}, not {want}");
        }
        let (a, b) = (tp.totals(5000.0).cut_length_mm, p.toolpath.totals(5000.0).cut_length_mm);
        assert!(a > 100.0 && ((a - b) / a).abs() < 1e-3, "{post:?}: cutting length {b} read, {a} written");
        // every feed move straight down is marked a plunge (swarf's descents through the air
        // among them: a program does not say where the stock is; the simulation tells)
        let down = tp.segments().filter(|(f, m)| !m.is_rapid() && m.to.z < f.z && m.to.truncate() == f.truncate());
        assert_eq!(p.toolpath.totals(5000.0).plunges, down.count(), "{post:?}");
    }
}
