//! Loads the sample DXFs of a swarf development checkout (`../shared/parts/dxf` beside the checkout, or the folder
//! in `SWARF_PARTS_DXF`), prints what was read and checks the known results. Ignored by default;
//! skips when the folder is missing, as it is in a user's clone.
//!
//! `cargo test -p swarf-import --test suite dxf_shared_files:: -- --ignored --nocapture`

use std::path::PathBuf;
use swarf_import::{ImportOptions, read_drawing};

/// What each sample must give: a number of closed contours, or an error containing a text.
const EXPECTED: &[(&str, Result<usize, &str>)] = &[
    ("camotics_camotics-text.dxf", Ok(11)),
    ("dxf2gcode_Lueftergitter_R14.dxf", Ok(16)),
    ("dxf2gcode_Stir_1.dxf", Ok(14)),
    ("dxf2gcode_pumpenteile.dxf", Err("2 gaps (3.000 mm between (23.000, 109.000) and (26.000, 109.000)")),
    ("pycam_simple-shapes.dxf", Ok(4)),
    ("trimesh_125_cycloidal.dxf", Ok(23)),
    ("trimesh_apu-mount.dxf", Ok(19)),
    ("trimesh_spline.dxf", Ok(4)),
    ("trimesh_wrench.dxf", Ok(2)),
];

#[test]
#[ignore = "needs the development sample files; prints a report"]
fn load_shared_dxf_files() {
    let dir = std::env::var_os("SWARF_PARTS_DXF")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/parts/dxf")));
    if !dir.is_dir() {
        eprintln!("{} is missing: nothing to check", dir.display());
        return;
    }
    let mut failures = Vec::new();
    for (name, expected) in EXPECTED {
        let path = dir.join(name);
        if !path.exists() {
            eprintln!("{name} is missing");
            continue;
        }
        let t = std::time::Instant::now();
        let got = read_drawing(&path, &ImportOptions::default());
        match &got {
            Ok(d) => {
                let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
                let (mut arcs, mut verts) = (0, 0);
                for s in &d.shapes {
                    let sb = s.contour.bounds().expect("non-empty contour");
                    b = [b[0].min(sb[0]), b[1].min(sb[1]), b[2].max(sb[2]), b[3].max(sb[3])];
                    arcs += s.contour.vertices.iter().filter(|v| v.bulge != 0.0).count();
                    verts += s.contour.vertices.len();
                }
                println!(
                    "{name}: {} closed contours ({verts} vertices, {arcs} arcs), units {:?}, \
                     x {:.3}..{:.3}, y {:.3}..{:.3}, extents {:.3} x {:.3} mm ({:.1?})",
                    d.shapes.len(),
                    d.units,
                    b[0],
                    b[2],
                    b[1],
                    b[3],
                    b[2] - b[0],
                    b[3] - b[1],
                    t.elapsed()
                );
            }
            Err(e) => println!("{name}: refused: {e}"),
        }
        let ok = match (expected, &got) {
            (Ok(n), Ok(d)) => d.shapes.len() == *n,
            (Err(text), Err(e)) => e.to_string().contains(text),
            _ => false,
        };
        if !ok {
            failures.push(format!("{name}: expected {expected:?}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
