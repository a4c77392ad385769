//! STL, the 3D printers' format: a reader for ascii and binary files (vertices welded by exact
//! position, so the mesh has its connectivity back) and a binary writer.
//!
//! Why by hand: `stl_io` (0.11) takes any file whose first line starts with `solid ` for ascii,
//! so it misreads the binary files many CAD exporters write with such a header, and it refuses
//! ascii files whose first line is a bare `solid`; its errors carry no line number. Here a file is
//! binary when its size is exactly `84 + 50 n` for the triangle count `n` in its header (the test
//! slicers use), and ascii otherwise when it starts with `solid`.

use super::{Coordinates, IoError};
use glam::Vec3;
use isolab_algorithms::TriMesh;
use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

/// Whether `bytes` are a binary STL: a triangle count in bytes 80..84 that gives the file's
/// exact size.
pub fn is_binary_stl(bytes: &[u8]) -> bool {
    bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        84 + 50 * n == bytes.len() as u64
    }
}

/// Parses STL bytes; `path` is only used in error messages.
pub fn parse_stl(bytes: &[u8], path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let mut welder = Welder::default();
    if is_binary_stl(bytes) {
        for (n, facet) in bytes[84..].chunks_exact(50).enumerate() {
            let f = |o: usize| f32::from_le_bytes([facet[o], facet[o + 1], facet[o + 2], facet[o + 3]]);
            let corners = [0, 1, 2].map(|k| Vec3::new(f(12 + 12 * k), f(16 + 12 * k), f(20 + 12 * k)));
            if coordinates == Coordinates::Finite && corners.iter().any(|c| !c.is_finite()) {
                return Err(IoError::Invalid { path: path.into(), reason: format!("triangle {n} has a non-finite coordinate") });
            }
            welder.triangle(corners);
        }
    } else if bytes.trim_ascii_start().starts_with(b"solid") {
        parse_ascii(bytes, path, coordinates, &mut welder)?;
    } else if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!(
                "not an STL file: it does not start with 'solid', and as binary STL its header's {n} triangles need {} bytes, \
                 but it has {}",
                84 + 50 * n,
                bytes.len()
            ),
        });
    } else {
        return Err(IoError::Invalid { path: path.into(), reason: format!("not an STL file ({} bytes)", bytes.len()) });
    }
    if welder.mesh.triangles.is_empty() {
        return Err(IoError::Empty { path: path.into(), vertices: welder.mesh.positions.len() });
    }
    Ok(welder.mesh)
}

/// Joins corners at the same position into one vertex (`-0.0` and `0.0` alike).
#[derive(Default)]
struct Welder {
    mesh: TriMesh,
    index: HashMap<[u32; 3], u32>,
}

impl Welder {
    fn triangle(&mut self, corners: [Vec3; 3]) {
        let t = corners.map(|p| {
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            *self.index.entry(key).or_insert_with(|| {
                self.mesh.positions.push(p);
                (self.mesh.positions.len() - 1) as u32
            })
        });
        self.mesh.triangles.push(t);
    }
}

fn parse_ascii(bytes: &[u8], path: &Path, coordinates: Coordinates, welder: &mut Welder) -> Result<(), IoError> {
    let text = String::from_utf8_lossy(bytes);
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let mut loop_corners: Vec<Vec3> = Vec::with_capacity(3);
    let mut in_loop = false;
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let words: Vec<&str> = raw.split_whitespace().collect();
        let Some(first) = words.first() else { continue };
        match first.to_ascii_lowercase().as_str() {
            "solid" | "endsolid" | "facet" | "endfacet" => {}
            "outer" => {
                if in_loop {
                    return Err(malformed(line, "'outer loop' inside a loop".into()));
                }
                in_loop = true;
                loop_corners.clear();
            }
            "vertex" => {
                if !in_loop {
                    return Err(malformed(line, "'vertex' outside 'outer loop' ... 'endloop'".into()));
                }
                if words.len() != 4 {
                    return Err(malformed(line, format!("vertex has {} coordinates, expected 3", words.len() - 1)));
                }
                let mut xyz = [0.0f32; 3];
                for (c, w) in xyz.iter_mut().zip(&words[1..]) {
                    *c = w.parse().map_err(|_| malformed(line, format!("'{}' is not a number", super::shown(w))))?;
                    if coordinates == Coordinates::Finite && !c.is_finite() {
                        return Err(malformed(line, format!("coordinate '{w}' is not finite")));
                    }
                }
                loop_corners.push(Vec3::from(xyz));
            }
            "endloop" => {
                if !in_loop || loop_corners.len() < 3 {
                    return Err(malformed(line, format!("a facet has {} vertices, at least 3 are needed", loop_corners.len())));
                }
                for k in 1..loop_corners.len() - 1 {
                    welder.triangle([loop_corners[0], loop_corners[k], loop_corners[k + 1]]);
                }
                in_loop = false;
            }
            _ => return Err(malformed(line, format!("unexpected '{}' in an ascii STL", super::shown(first)))),
        }
    }
    if in_loop {
        return Err(malformed(text.lines().count(), "the file ends inside a facet".into()));
    }
    Ok(())
}

/// Binary STL: an 80-byte header (`header`, padded with spaces; 3D Slicer reads `SPACE=RAS`
/// there), the triangle count, then per triangle its unit normal, three corners and a zero
/// attribute. Every triangle's corners are stored, so the file has no shared vertices.
pub fn write_stl(w: &mut impl Write, mesh: &TriMesh, header: &str) -> std::io::Result<()> {
    let mut head = [b' '; 80];
    let text = header.as_bytes();
    head[..text.len().min(80)].copy_from_slice(&text[..text.len().min(80)]);
    w.write_all(&head)?;
    w.write_all(&(mesh.triangles.len() as u32).to_le_bytes())?;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for v in [normal, a, b, c] {
            for x in v.to_array() {
                w.write_all(&x.to_le_bytes())?;
            }
        }
        w.write_all(&[0, 0])?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> TriMesh {
        TriMesh::unit_tetrahedron()
    }

    #[test]
    fn binary_round_trip_welds_vertices_even_with_a_solid_header() {
        let mut bytes = Vec::new();
        write_stl(&mut bytes, &tetrahedron(), "solid exported by a CAD tool").unwrap();
        assert_eq!(bytes.len(), 84 + 4 * 50);
        let back = parse_stl(&bytes, Path::new("t.stl"), Coordinates::Finite).unwrap();
        // Vertices are numbered as first met; the triangles are the same.
        assert_eq!(back.positions.len(), 4);
        assert_eq!(super::super::soup(&back), super::super::soup(&tetrahedron()));
    }

    #[test]
    fn ascii_with_a_bare_solid_line_and_quads() {
        let text =
            "solid\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  \
                    endloop\n endfacet\nendsolid\n";
        let m = parse_stl(text.as_bytes(), Path::new("q.stl"), Coordinates::Finite).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn faults_name_the_line() {
        let p = Path::new("bad.stl");
        let text = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 zero 0\nvertex 0 1 0\nendloop\nendfacet\n";
        let e = parse_stl(text.as_bytes(), p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.starts_with("bad.stl:5:") && e.contains("'zero'"), "{e}");
        let e = parse_stl(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", p, Coordinates::Finite)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ends inside a facet"), "{e}");
        let mut bytes = Vec::new();
        write_stl(&mut bytes, &tetrahedron(), "isolab").unwrap();
        let e = parse_stl(&bytes[..bytes.len() - 10], p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.contains("need 284 bytes") && e.contains("274"), "{e}");
        assert!(matches!(parse_stl(b"solid empty\nendsolid empty\n", p, Coordinates::Finite), Err(IoError::Empty { .. })));
    }
}
