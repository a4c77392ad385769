//! Wavefront OBJ: a reader that names the file and line of any error, and a writer (with
//! optional `v x y z r g b` vertex colours).
//!
//! Why not `tobj` for reading: its errors do not say which line is malformed, and the CLI promises
//! that they do. OBJ's geometry subset (`v`, `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` and negative
//! indices, polygons fan-triangulated) is small enough to parse here; every other statement
//! (`vn`, `vt`, `o`, `g`, `s`, `usemtl`, `mtllib`, ...) is ignored.

use super::{Coordinates, IoError};
use glam::Vec3;
use isolab_algorithms::TriMesh;
use std::io::Write;
use std::path::Path;

/// Parses OBJ text; `path` is only used in error messages.
pub fn parse_obj(text: &str, path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let mut mesh = TriMesh::default();
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let mut face = Vec::with_capacity(8);
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut xyz = [0.0f32; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let w = words.next().ok_or_else(|| malformed(line, format!("vertex has {k} coordinates, expected 3")))?;
                    *c = w.parse().map_err(|_| malformed(line, format!("'{}' is not a number", super::shown(w))))?;
                    if !c.is_finite() && coordinates == Coordinates::Finite {
                        return Err(malformed(line, format!("coordinate '{w}' is not finite")));
                    }
                }
                mesh.positions.push(Vec3::from(xyz));
            }
            Some("f") => {
                face.clear();
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let i: i64 = first
                        .parse()
                        .map_err(|_| malformed(line, format!("face index '{}' is not an integer", super::shown(w))))?;
                    let count = mesh.positions.len() as i64;
                    let resolved = if i > 0 { i - 1 } else { count + i };
                    if i == 0 || resolved < 0 || resolved >= count {
                        return Err(malformed(line, format!("face index {i} is out of range: {count} vertices defined so far")));
                    }
                    face.push(resolved as u32);
                }
                if face.len() < 3 {
                    return Err(malformed(line, format!("face has {} vertices, at least 3 are needed", face.len())));
                }
                for k in 1..face.len() - 1 {
                    mesh.triangles.push([face[0], face[k], face[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if mesh.triangles.is_empty() {
        return Err(IoError::Empty { path: path.into(), vertices: mesh.positions.len() });
    }
    Ok(mesh)
}

/// OBJ with optional vertex colours (`v x y z r g b`, components in [0, 1]) and an optional
/// comment line naming the coordinate system (`# SPACE=RAS`, which 3D Slicer reads).
pub fn write_obj_coloured(
    w: &mut impl Write,
    mesh: &TriMesh,
    colours: Option<&[[u8; 3]]>,
    space: Option<&str>,
) -> std::io::Result<()> {
    writeln!(w, "# isolab: {} vertices, {} triangles", mesh.positions.len(), mesh.triangles.len())?;
    if let Some(space) = space {
        writeln!(w, "# SPACE={space}")?;
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        match colours {
            Some(c) => {
                let [r, g, b] = c[i].map(|v| f32::from(v) / 255.0);
                writeln!(w, "v {} {} {} {r:.4} {g:.4} {b:.4}", p.x, p.y, p.z)?
            }
            None => writeln!(w, "v {} {} {}", p.x, p.y, p.z)?,
        }
    }
    let normals = mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty();
    if normals {
        for n in &mesh.normals {
            writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        if normals {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_errors_name_the_line() {
        let p = Path::new("m.obj");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.starts_with("m.obj:4:"), "{e}");
        let e = parse_obj("v 0 0 0\nv 1 zero 0\n", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.starts_with("m.obj:2:"), "{e}");
        let e = parse_obj("v 0 0 0\nf 1 2 3\n", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.contains(":2:") && e.contains("out of range"), "{e}");
        assert!(matches!(parse_obj("# nothing\n", p, Coordinates::Finite), Err(IoError::Empty { .. })));
    }

    #[test]
    fn obj_polygons_and_negative_indices() {
        let m = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2//2 3 -1\n", Path::new("q.obj"), Coordinates::Finite)
            .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }
}
