//! STL meshes, binary and ASCII.
//!
//! Written by hand rather than with a crate: the reader must name the place of every defect in
//! the file (the line of an ASCII facet, the index and byte offset of a binary one), tell the
//! two encodings apart by the file's size rather than by its first word (binary files from
//! several exporters start with `solid`), and keep going over degenerate facets, which it drops
//! and counts; the STL readers on crates.io return a bare `io::Error` and stop at the first
//! oddity.
//!
//! A binary STL is an 80-byte header, a little-endian `u32` facet count and 50 bytes per facet
//! (normal, three vertices as `f32`, a 2-byte attribute); the file is binary exactly when its size
//! is `84 + 50·n`. An ASCII STL is `solid name`, facets `facet normal nx ny nz / outer loop /
//! vertex x y z` ×3 `/ endloop / endfacet`, and `endsolid`; several solids may follow each other.
//! The normals are ignored (the vertex order gives the orientation, and many files have zero or
//! wrong normals).

use crate::error::{Error, Result};
use crate::geom::DVec3;
use crate::geom::mesh::Mesh;
use std::path::Path;

/// Relative area below which a facet counts as degenerate (of the square of its longest edge).
const DEGENERATE: f64 = 1e-12;

/// How a part drawn sideways lies: the axis its flat faces mostly face (0: X, 1: Y), their
/// area and the area facing Z, and the flat area on each of the two faces of its bounding box
/// across that axis (the low side's, facing down the axis, and the high side's). Flat faces are
/// those whose normal is within 2.6° of an axis; sideways must have at least 1.5 times the area
/// facing Z, and the part must be thinnest along that axis (under 0.8 of its other extents: a
/// tower, thin in X and Y alike, is left alone).
struct Sideways {
    axis: usize,
    side: f64,
    up: f64,
    ends: [f64; 2],
}

fn sideways(mesh: &Mesh) -> Option<Sideways> {
    let (lo, hi) = mesh.bounds()?;
    let ext = hi - lo;
    let mut by_axis = [0.0f64; 3];
    // flat area on the box's faces across X and Y: [axis][low, high]
    let mut ends = [[0.0f64; 2]; 2];
    let tol = 1e-4 * ext.max_element();
    for [a, b, c] in &mesh.tris {
        let n = (*b - *a).cross(*c - *a);
        let len = n.length();
        if len.is_nan() || len <= 0.0 {
            continue;
        }
        let u = n / len;
        for (k, s) in by_axis.iter_mut().enumerate() {
            if u[k].abs() > 0.999 {
                *s += 0.5 * len;
                if k < 2 {
                    let (vmin, vmax) = (a[k].min(b[k]).min(c[k]), a[k].max(b[k]).max(c[k]));
                    if u[k] < 0.0 && vmax <= lo[k] + tol {
                        ends[k][0] += 0.5 * len;
                    } else if u[k] > 0.0 && vmin >= hi[k] - tol {
                        ends[k][1] += 0.5 * len;
                    }
                }
            }
        }
    }
    let (k, side) = if by_axis[1] >= by_axis[0] { (1, by_axis[1]) } else { (0, by_axis[0]) };
    let thinnest = (0..3).filter(|&j| j != k).all(|j| ext[k] < 0.8 * ext[j]);
    (side > 1.5 * by_axis[2] && thinnest).then_some(Sideways { axis: k, side, up: by_axis[2], ends: ends[k] })
}

/// A warning when the part's flat faces mostly face sideways (X or Y) rather than up (see
/// `Sideways`): a part drawn Y-up (or X-up) would be roughed standing on its edge.
pub fn orientation_warning(mesh: &Mesh) -> Option<String> {
    let s = sideways(mesh)?;
    let (axis, fix) = if s.axis == 1 { ("Y", "90,0,0 or -90,0,0") } else { ("X", "0,90,0 or 0,-90,0") };
    Some(format!(
        "most of its flat faces face {axis} ({:.0} mm² against {:.0} mm² facing Z): if it was drawn {axis}-up, --part-rotate {fix} lays it flat (whichever puts the side to cut on top)",
        s.side, s.up
    ))
}

/// The rotation that lays a part drawn sideways (see `Sideways`) flat on its back: of the two
/// faces of its bounding box across the axis its flats face, the one with clearly more flat
/// area on it (a tenth more: the whole back against the parting face round a cavity, say)
/// goes down, and the other side, which holds what there is to cut, faces up. The rotation (as
/// `--part-rotate` takes it, degrees about X, Y, Z) and what was done, in words; none when the
/// part is not sideways or its two sides are too alike to tell.
pub fn lay_flat(mesh: &Mesh) -> Option<([f64; 3], String)> {
    let s = sideways(mesh)?;
    let [low, high] = s.ends;
    let (down_is_high, more, less) = if high >= low { (true, high, low) } else { (false, low, high) };
    if more < 1.1 * less || more <= 0.0 {
        return None;
    }
    // (+Y down: -90° about X; -Y down: +90°; +X down: +90° about Y; -X down: -90°)
    let (facing, face, angle, about) = match (s.axis, down_is_high) {
        (1, true) => ("Y", "+Y", -90.0, "X"),
        (1, false) => ("Y", "-Y", 90.0, "X"),
        (_, true) => ("X", "+X", 90.0, "Y"),
        (_, false) => ("X", "-X", -90.0, "Y"),
    };
    let rot = if about == "X" { [angle, 0.0, 0.0] } else { [0.0, angle, 0.0] };
    let what = format!(
        "laid flat: its flat faces face {facing} ({:.0} mm² against {:.0} mm² facing Z), the {face} side ({more:.0} mm² of flat face against {less:.0}) is its back: rotated {angle:+.0}° about {about} (--part-rotate 0,0,0 keeps it as drawn)",
        s.side, s.up,
    );
    Some((rot, what))
}

/// Refuses a mesh, placed, that reaches beyond [`crate::limits::MAX_COORD_MM`], as an error of
/// `path` at `place` (`what` says what placed it, for the message).
pub fn check_size(path: &Path, mesh: &Mesh, place: &str, what: &str) -> Result<()> {
    let Some((lo, hi)) = mesh.bounds() else { return Ok(()) };
    match crate::limits::reach_refusal(&lo.to_array(), &hi.to_array()) {
        None => Ok(()),
        Some(why) => Err(Error::input(path, place, format!("placed, {why} (are {what} right?)"))),
    }
}

/// Reads an STL file.
pub fn read(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
    parse(path, &bytes)
}

/// Parses the bytes of an STL file (`path` names it in errors).
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let mesh = if is_binary(bytes) {
        parse_binary(path, bytes)?
    } else if starts_with_solid(bytes) {
        parse_ascii(path, bytes)?
    } else if bytes.len() < 84 {
        return Err(Error::input(
            path,
            "file",
            format!(
                "{} bytes: too short for a binary STL (84 bytes of header) and not ASCII STL (no \"solid\")",
                bytes.len()
            ),
        ));
    } else {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        return Err(Error::input(
            path,
            "file",
            format!(
                "not an STL file: not ASCII (does not start with \"solid\") and not binary (the header counts {n} facets, which take {} bytes, but the file has {})",
                84 + 50 * n,
                bytes.len()
            ),
        ));
    };
    not_empty(path, mesh)
}

/// The mesh, or an error when it has no facet left (none read, or all degenerate).
fn not_empty(path: &Path, mesh: Mesh) -> Result<Mesh> {
    if mesh.tris.is_empty() {
        return Err(Error::input(
            path,
            "file",
            if mesh.dropped > 0 {
                format!("all {} facets are degenerate (zero area): no surface to machine", mesh.dropped)
            } else {
                "the mesh has no facets".to_string()
            },
        ));
    }
    Ok(mesh)
}

/// A mesh from vertices and triangles (indices into the vertices, counter-clockwise seen from
/// outside), checked as a file's facets are: coordinates finite and within the numbers swarf
/// reads, indices in range, degenerate triangles dropped, at least one left. `path` names the
/// mesh in errors, which name the triangle or vertex.
pub fn from_triangles(path: &Path, vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> Result<Mesh> {
    for (i, v) in vertices.iter().enumerate() {
        let p = DVec3::from_array(*v);
        if !(p.is_finite() && p.abs().max_element() <= crate::limits::MAX_NUMBER) {
            return Err(Error::input(
                path,
                format!("vertices[{i}]"),
                format!("coordinate is not a finite number within ±{:e} ({p})", crate::limits::MAX_NUMBER),
            ));
        }
    }
    let mut mesh = Mesh { tris: Vec::with_capacity(triangles.len()), dropped: 0, binary: false };
    for (i, t) in triangles.iter().enumerate() {
        let mut tri = [DVec3::ZERO; 3];
        for (k, &ix) in t.iter().enumerate() {
            let v = vertices.get(ix).ok_or_else(|| {
                Error::input(path, format!("triangles[{i}]"), format!("vertex {ix} of {} vertices", vertices.len()))
            })?;
            tri[k] = DVec3::from_array(*v);
        }
        push(&mut mesh, tri);
    }
    not_empty(path, mesh)
}

fn is_binary(bytes: &[u8]) -> bool {
    bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        bytes.len() as u64 == 84 + 50 * n
    }
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let s = bytes.iter().position(|b| !b.is_ascii_whitespace()).map_or(&[][..], |i| &bytes[i..]);
    s.len() >= 5 && s[..5].eq_ignore_ascii_case(b"solid")
}

/// Adds a facet unless it is degenerate.
fn push(mesh: &mut Mesh, t: [DVec3; 3]) {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let l2 = (t[1] - t[0]).length_squared().max((t[2] - t[1]).length_squared()).max((t[0] - t[2]).length_squared());
    if n.length_squared() <= DEGENERATE * l2 * l2 || l2 == 0.0 {
        mesh.dropped += 1;
    } else {
        mesh.tris.push(t);
    }
}

fn parse_binary(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let mut mesh = Mesh { tris: Vec::with_capacity(n), dropped: 0, binary: true };
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64;
    for i in 0..n {
        let o = 84 + 50 * i;
        let mut t = [DVec3::ZERO; 3];
        for (k, v) in t.iter_mut().enumerate() {
            let b = o + 12 + 12 * k;
            *v = DVec3::new(f(b), f(b + 4), f(b + 8));
            if !(v.is_finite() && v.abs().max_element() <= crate::limits::MAX_NUMBER) {
                return Err(Error::input(
                    path,
                    format!("facet {} (byte {}), vertex {}", i + 1, b, k + 1),
                    format!("coordinate is not a finite number within ±{:e} ({v})", crate::limits::MAX_NUMBER),
                ));
            }
        }
        push(&mut mesh, t);
    }
    Ok(mesh)
}

fn parse_ascii(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::input(path, format!("line {line}"), "not UTF-8 text, and the size does not fit a binary STL")
    })?;
    // tokens with their line numbers
    let mut toks = text.lines().enumerate().flat_map(|(i, l)| l.split_whitespace().map(move |w| (i + 1, w))).peekable();
    let mut mesh = Mesh::default();
    let mut last_line = 1;
    let err = |line: usize, what: String| Error::input(path, format!("line {line}"), what);
    macro_rules! next {
        ($what:expr) => {
            match toks.next() {
                Some((l, w)) => {
                    last_line = l;
                    (l, w)
                }
                None => return Err(err(last_line, format!("unexpected end of file: expected {}", $what))),
            }
        };
    }
    macro_rules! expect {
        ($word:expr) => {{
            let (l, w) = next!(format!("\"{}\"", $word));
            if !w.eq_ignore_ascii_case($word) {
                return Err(err(l, format!("expected \"{}\", found \"{}\"", $word, w)));
            }
        }};
    }
    let mut solids = 0;
    while toks.peek().is_some() {
        let (l, w) = next!("\"solid\"");
        if !w.eq_ignore_ascii_case("solid") {
            return Err(err(l, format!("expected \"solid\", found \"{w}\"")));
        }
        solids += 1;
        // the name: the rest of the line
        while toks.peek().is_some_and(|(ll, _)| *ll == l) {
            toks.next();
        }
        loop {
            let (l, w) = next!("\"facet\" or \"endsolid\"");
            if w.eq_ignore_ascii_case("endsolid") {
                while toks.peek().is_some_and(|(ll, _)| *ll == l) {
                    toks.next();
                }
                break;
            }
            if !w.eq_ignore_ascii_case("facet") {
                return Err(err(l, format!("expected \"facet\" or \"endsolid\", found \"{w}\"")));
            }
            expect!("normal");
            for _ in 0..3 {
                let (l, w) = next!("a normal component");
                w.parse::<f64>().map_err(|_| err(l, format!("normal component \"{w}\" is not a number")))?;
            }
            expect!("outer");
            expect!("loop");
            let mut t = [DVec3::ZERO; 3];
            for v in &mut t {
                expect!("vertex");
                let mut c = [0.0; 3];
                for x in &mut c {
                    let (l, w) = next!("a vertex coordinate");
                    *x = w
                        .parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite() && x.abs() <= crate::limits::MAX_NUMBER)
                        .ok_or_else(|| {
                            err(
                                l,
                                format!(
                                    "vertex coordinate \"{w}\" is not a finite number within ±{:e}",
                                    crate::limits::MAX_NUMBER
                                ),
                            )
                        })?;
                }
                *v = DVec3::from_array(c);
            }
            let (l, w) = next!("\"endloop\"");
            if w.eq_ignore_ascii_case("vertex") {
                return Err(err(l, "a facet with more than 3 vertices (only triangles are STL)".to_string()));
            }
            if !w.eq_ignore_ascii_case("endloop") {
                return Err(err(l, format!("expected \"endloop\", found \"{w}\"")));
            }
            expect!("endfacet");
            push(&mut mesh, t);
        }
    }
    if solids == 0 {
        return Err(err(1, "no \"solid\"".to_string()));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::Placement;

    const CUBE_FACETS: [[[f64; 3]; 3]; 2] =
        [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]]];

    fn ascii(facets: &[[[f64; 3]; 3]]) -> String {
        let mut s = String::from("solid test\n");
        for f in facets {
            s += "  facet normal 0 0 1\n    outer loop\n";
            for v in f {
                s += &format!("      vertex {} {} {}\n", v[0], v[1], v[2]);
            }
            s += "    endloop\n  endfacet\n";
        }
        s + "endsolid test\n"
    }

    fn binary(facets: &[[[f64; 3]; 3]], header: &[u8]) -> Vec<u8> {
        let mut b = vec![0u8; 80];
        b[..header.len()].copy_from_slice(header);
        b.extend((facets.len() as u32).to_le_bytes());
        for f in facets {
            b.extend([0u8; 12]);
            for v in f {
                for x in v {
                    b.extend((*x as f32).to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        b
    }

    #[test]
    fn reads_ascii_and_binary_alike() {
        let p = Path::new("t.stl");
        let a = parse(p, ascii(&CUBE_FACETS).as_bytes()).unwrap();
        // a binary file whose header starts with "solid" is still binary
        let b = parse(p, &binary(&CUBE_FACETS, b"solid but binary")).unwrap();
        assert!(!a.binary && b.binary);
        assert_eq!(a.tris, b.tris);
        assert_eq!(a.tris.len(), 2);
        assert_eq!(a.bounds().unwrap(), (DVec3::ZERO, DVec3::ONE));
    }

    #[test]
    fn drops_degenerate_facets() {
        let mut f = CUBE_FACETS.to_vec();
        f.push([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]);
        let m = parse(Path::new("t.stl"), ascii(&f).as_bytes()).unwrap();
        assert_eq!((m.tris.len(), m.dropped), (2, 1));
        let e = parse(Path::new("t.stl"), ascii(&f[2..]).as_bytes()).unwrap_err().to_string();
        assert!(e.contains("degenerate"), "{e}");
    }

    #[test]
    fn names_the_line_of_a_bad_ascii_facet() {
        let text = ascii(&CUBE_FACETS).replacen("vertex 1 1 0", "vertex 1 x 0", 1);
        let e = parse(Path::new("bad.stl"), text.as_bytes()).unwrap_err().to_string();
        assert!(e.starts_with("bad.stl: line 6: vertex coordinate \"x\""), "{e}");
        let text = ascii(&CUBE_FACETS).replacen("endloop", "vertex 0 0 0", 1);
        let e = parse(Path::new("bad.stl"), text.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("line 7") && e.contains("more than 3 vertices"), "{e}");
        let text = &ascii(&CUBE_FACETS)[..60];
        let e = parse(Path::new("bad.stl"), text.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("unexpected end of file"), "{e}");
    }

    #[test]
    fn names_a_truncated_binary_file() {
        let mut b = binary(&CUBE_FACETS, b"bin");
        b.truncate(b.len() - 7);
        let e = parse(Path::new("cut.stl"), &b).unwrap_err().to_string();
        assert!(e.contains("header counts 2 facets, which take 184 bytes, but the file has 177"), "{e}");
        let mut b = binary(&CUBE_FACETS, b"bin");
        b[84 + 12..84 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = parse(Path::new("nan.stl"), &b).unwrap_err().to_string();
        assert!(e.contains("facet 1 (byte 96), vertex 1"), "{e}");
    }

    #[test]
    fn places_a_y_up_inch_part() {
        let mut m = parse(Path::new("t.stl"), ascii(&CUBE_FACETS).as_bytes()).unwrap();
        m.transform(&Placement { scale: 25.4, rotate_deg: [-90.0, 0.0, 0.0], translate: DVec3::new(0.0, 0.0, 1.0) });
        let (lo, hi) = m.bounds().unwrap();
        // (x, y, z) → (x, z, −y)
        assert!((lo - DVec3::new(0.0, 0.0, -24.4)).length() < 1e-9, "{lo}");
        assert!((hi - DVec3::new(25.4, 25.4, 1.0)).length() < 1e-9, "{hi}");
    }

    #[test]
    fn counts_open_edges() {
        let m = parse(Path::new("t.stl"), ascii(&CUBE_FACETS).as_bytes()).unwrap();
        assert_eq!(m.open_edges(1e-6), 6);
    }
}
