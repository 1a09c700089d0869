//! Loads the sample SVGs of a swarf development checkout (`../shared/parts/svg` beside the checkout, or the folder
//! in `SWARF_PARTS_SVG`) and prints what was read. Ignored by default; skips when the folder is
//! missing, as it is in a user's clone.
//!
//! `cargo test -p swarf-import --test suite svg_shared_files:: -- --ignored --nocapture`

use std::path::PathBuf;
use swarf_import::{ImportOptions, read_drawing};

#[test]
#[ignore = "needs the development sample files; prints a report"]
fn load_shared_svg_files() {
    let dir = std::env::var_os("SWARF_PARTS_SVG")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/parts/svg")));
    let Ok(entries) = std::fs::read_dir(&dir) else {
        eprintln!("{} is missing: nothing to check", dir.display());
        return;
    };
    let mut files: Vec<PathBuf> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
    files.sort();
    for f in files.iter().filter(|f| f.extension().is_some_and(|e| e == "svg")) {
        for ppi in [96.0, 90.0] {
            let opts = ImportOptions { svg_px_per_inch: Some(ppi), ..Default::default() };
            match read_drawing(f, &opts) {
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
                        "{} @{ppi} px/in: {} closed contours ({verts} vertices, {arcs} arcs), units {:?}, \
                         x {:.3}..{:.3}, y {:.3}..{:.3}, extents {:.3} x {:.3} mm",
                        f.file_name().unwrap().to_string_lossy(),
                        d.shapes.len(),
                        d.units,
                        b[0],
                        b[2],
                        b[1],
                        b[3],
                        b[2] - b[0],
                        b[3] - b[1]
                    );
                    for s in &d.shapes {
                        println!(
                            "    {:?} layer {:?} area {:.3} vertices {} : {}",
                            s.role,
                            s.layer,
                            s.contour.signed_area(),
                            s.contour.vertices.len(),
                            s.origin
                        );
                    }
                }
                Err(e) => println!("{} @{ppi} px/in: ERROR {e}", f.file_name().unwrap().to_string_lossy()),
            }
        }
    }
}
