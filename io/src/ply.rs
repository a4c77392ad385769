//! Stanford PLY: a reader for every PLY a mesh tool writes (ascii, binary little- and
//! big-endian; any scalar type for coordinates; face lists with any count and index types; extra
//! properties and elements, which are skipped), and a binary little-endian writer.
//!
//! Why by hand: the Rust PLY crates (`ply-rs` and its forks) parse into a dynamic map per
//! element with no line numbers in their errors; what isolab needs from PLY is positions and
//! faces, with a message naming the line (ascii) or byte (binary) of any fault, from bytes in
//! memory (so it can be fuzzed). The header grammar is a dozen keywords.

use super::{Coordinates, IoError};
use glam::Vec3;
use isolab_algorithms::TriMesh;
use std::io::Write;
use std::path::Path;

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Clone, Debug)]
enum Kind {
    Scalar(Scalar),
    /// Count type, item type.
    List(Scalar, Scalar),
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Lines in the header (ascii body lines are numbered after them).
    lines: usize,
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, IoError> {
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let mut at = 0;
    let mut line = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let end = bytes[at..].iter().position(|&b| b == b'\n').map(|p| at + p).ok_or_else(|| {
            if line == 0 {
                IoError::Invalid { path: path.into(), reason: "not a PLY file: it does not start with a 'ply' line".into() }
            } else {
                malformed(line, "the header has no 'end_header' line".into())
            }
        })?;
        line += 1;
        let text = String::from_utf8_lossy(&bytes[at..end]);
        at = end + 1;
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if words.as_slice() != ["ply"] {
                return Err(IoError::Invalid {
                    path: path.into(),
                    reason: "not a PLY file: it does not start with a 'ply' line".into(),
                });
            }
            continue;
        }
        match words.as_slice() {
            ["format", f, _version] => {
                encoding = Some(match *f {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    other => return Err(malformed(line, format!("unknown format '{}'", super::shown(other)))),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count = count
                    .parse()
                    .map_err(|_| malformed(line, format!("element count '{}' is not a count", super::shown(count))))?;
                elements.push(Element { name: (*name).into(), count, properties: Vec::new() });
            }
            ["property", "list", count, item, name] => {
                let element = elements.last_mut().ok_or_else(|| malformed(line, "a property before any element".into()))?;
                let scalar =
                    |t: &str| Scalar::parse(t).ok_or_else(|| malformed(line, format!("unknown type '{}'", super::shown(t))));
                let (count, item) = (scalar(count)?, scalar(item)?);
                if !count.is_integer() {
                    return Err(malformed(line, format!("list count type '{}' is not an integer type", words[2])));
                }
                element.properties.push(Property { name: (*name).into(), kind: Kind::List(count, item) });
            }
            ["property", ty, name] => {
                let element = elements.last_mut().ok_or_else(|| malformed(line, "a property before any element".into()))?;
                let ty = Scalar::parse(ty).ok_or_else(|| malformed(line, format!("unknown type '{}'", super::shown(ty))))?;
                element.properties.push(Property { name: (*name).into(), kind: Kind::Scalar(ty) });
            }
            ["end_header"] => break,
            _ => return Err(malformed(line, format!("unexpected header line '{}'", super::shown(text.trim())))),
        }
    }
    let encoding = encoding.ok_or_else(|| malformed(1, "the header has no 'format' line".into()))?;
    Ok(Header { encoding, elements, body: at, lines: line })
}

/// Where the body reader is, for error messages.
trait Body {
    /// The next scalar as f64 (integers exactly up to 2^53).
    fn next(&mut self, ty: Scalar) -> Result<f64, String>;
    /// "line N" or "byte N".
    fn place(&self) -> String;
    /// The ascii line number, if any (0 for binary).
    fn line(&self) -> usize;
}

struct Binary<'a> {
    bytes: &'a [u8],
    at: usize,
    big: bool,
}

impl Body for Binary<'_> {
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        let n = ty.size();
        let s = self.bytes.get(self.at..self.at + n).ok_or_else(|| "the file ends early".to_owned())?;
        self.at += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(s);
        if self.big {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
    fn place(&self) -> String {
        format!("byte {}", self.at)
    }
    fn line(&self) -> usize {
        0
    }
}

struct Ascii<'a> {
    bytes: &'a [u8],
    at: usize,
    line: usize,
}

impl Body for Ascii<'_> {
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        while let Some(&b) = self.bytes.get(self.at) {
            if b == b'\n' {
                self.line += 1;
            } else if !b.is_ascii_whitespace() {
                break;
            }
            self.at += 1;
        }
        let start = self.at;
        while self.bytes.get(self.at).is_some_and(|b| !b.is_ascii_whitespace()) {
            self.at += 1;
        }
        if start == self.at {
            return Err("the file ends early".into());
        }
        let word = String::from_utf8_lossy(&self.bytes[start..self.at]);
        if ty.is_integer() {
            word.parse::<i64>().map(|v| v as f64).map_err(|_| format!("'{}' is not an integer", super::shown(&word)))
        } else {
            word.parse::<f64>().map_err(|_| format!("'{}' is not a number", super::shown(&word)))
        }
    }
    fn place(&self) -> String {
        format!("line {}", self.line)
    }
    fn line(&self) -> usize {
        self.line
    }
}

/// Parses PLY bytes; `path` is only used in error messages.
pub fn parse_ply(bytes: &[u8], path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let header = parse_header(bytes, path)?;
    let body = &bytes[header.body..];
    match header.encoding {
        Encoding::Ascii => read_body(&header, &mut Ascii { bytes: body, at: 0, line: header.lines + 1 }, path, coordinates),
        e => read_body(&header, &mut Binary { bytes: body, at: 0, big: e == Encoding::BigEndian }, path, coordinates),
    }
}

fn read_body(header: &Header, body: &mut impl Body, path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let fault = |body: &dyn Body, reason: String| {
        if body.line() > 0 {
            IoError::Malformed { path: path.into(), line: body.line(), reason }
        } else {
            IoError::Invalid { path: path.into(), reason: format!("{}: {reason}", body.place()) }
        }
    };
    let mut mesh = TriMesh::default();
    for element in &header.elements {
        if element.count == 0 {
            continue;
        }
        let is_vertex = element.name == "vertex";
        let is_face = element.name == "face";
        let xyz = if is_vertex {
            let find = |c: &str| element.properties.iter().position(|p| p.name == c && matches!(p.kind, Kind::Scalar(_)));
            match (find("x"), find("y"), find("z")) {
                (Some(x), Some(y), Some(z)) => Some([x, y, z]),
                _ => {
                    let reason = "the vertex element has no scalar x, y and z properties".into();
                    return Err(IoError::Invalid { path: path.into(), reason });
                }
            }
        } else {
            None
        };
        let indices = if is_face {
            let list = element
                .properties
                .iter()
                .position(|p| (p.name == "vertex_indices" || p.name == "vertex_index") && matches!(p.kind, Kind::List(..)));
            let reason = "the face element has no vertex_indices list".to_owned();
            Some(list.ok_or_else(|| IoError::Invalid { path: path.into(), reason })?)
        } else {
            None
        };
        if element.properties.is_empty() {
            continue;
        }
        let mut face = Vec::with_capacity(8);
        for n in 0..element.count {
            let mut point = [0.0f64; 3];
            for (k, property) in element.properties.iter().enumerate() {
                match property.kind {
                    Kind::Scalar(ty) => {
                        let v = body.next(ty).map_err(|e| fault(body, format!("{} {n}: {e}", element.name)))?;
                        if let Some(axis) = xyz.and_then(|xyz| xyz.iter().position(|&a| a == k)) {
                            point[axis] = v;
                        }
                    }
                    Kind::List(count_ty, item_ty) => {
                        let count = body.next(count_ty).map_err(|e| fault(body, format!("{} {n}: {e}", element.name)))?;
                        if !(0.0..=f64::from(u32::MAX)).contains(&count) {
                            return Err(fault(
                                body,
                                format!("{} {n}: list length {count} is negative or too large", element.name),
                            ));
                        }
                        let wanted = indices == Some(k);
                        face.clear();
                        for _ in 0..count as usize {
                            let v = body.next(item_ty).map_err(|e| fault(body, format!("{} {n}: {e}", element.name)))?;
                            if wanted {
                                if v < 0.0 || v.fract() != 0.0 || v > f64::from(u32::MAX) {
                                    return Err(fault(body, format!("face {n}: vertex index {v} is not a vertex index")));
                                }
                                face.push(v as u32);
                            }
                        }
                        if wanted {
                            if face.len() < 3 {
                                return Err(fault(body, format!("face {n} has {} vertices, at least 3 are needed", face.len())));
                            }
                            for k in 1..face.len() - 1 {
                                mesh.triangles.push([face[0], face[k], face[k + 1]]);
                            }
                        }
                    }
                }
            }
            if is_vertex {
                let p = Vec3::new(point[0] as f32, point[1] as f32, point[2] as f32);
                if coordinates == Coordinates::Finite && !p.is_finite() {
                    return Err(fault(body, format!("vertex {n} has a non-finite coordinate ({p})")));
                }
                mesh.positions.push(p);
            }
        }
    }
    let vertices = mesh.positions.len();
    if let Some((n, t)) = mesh.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&i| i as usize >= vertices)) {
        let bad = t.iter().find(|&&i| i as usize >= vertices).copied().unwrap_or_default();
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!("triangle {n} refers to vertex {bad}, but there are only {vertices} vertices"),
        });
    }
    if mesh.triangles.is_empty() {
        return Err(IoError::Empty { path: path.into(), vertices });
    }
    Ok(mesh)
}

/// Binary little-endian PLY: float x y z (and nx ny nz), faces as `uchar int` lists.
pub fn write_ply(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    write_ply_coloured(w, mesh, None, None)
}

/// Binary PLY with optional `uchar red green blue` vertex colours after the floats, and an
/// optional `comment SPACE=...` naming the coordinate system (3D Slicer reads it).
pub fn write_ply_coloured(
    w: &mut impl Write,
    mesh: &TriMesh,
    colours: Option<&[[u8; 3]]>,
    space: Option<&str>,
) -> std::io::Result<()> {
    let normals = mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty();
    writeln!(w, "ply\nformat binary_little_endian 1.0\ncomment isolab")?;
    if let Some(space) = space {
        writeln!(w, "comment SPACE={space}")?;
    }
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    writeln!(w, "property float x\nproperty float y\nproperty float z")?;
    if normals {
        writeln!(w, "property float nx\nproperty float ny\nproperty float nz")?;
    }
    if colours.is_some() {
        writeln!(w, "property uchar red\nproperty uchar green\nproperty uchar blue")?;
    }
    writeln!(w, "element face {}\nproperty list uchar int vertex_indices\nend_header", mesh.triangles.len())?;
    for (i, p) in mesh.positions.iter().enumerate() {
        for c in p.to_array() {
            w.write_all(&c.to_le_bytes())?;
        }
        if normals {
            for c in mesh.normals[i].to_array() {
                w.write_all(&c.to_le_bytes())?;
            }
        }
        if let Some(c) = colours {
            w.write_all(&c[i])?;
        }
    }
    for t in &mesh.triangles {
        w.write_all(&[3u8])?;
        for &i in t {
            w.write_all(&(i as i32).to_le_bytes())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII_QUAD: &str = "ply\r\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty double x\nproperty double y\n\
        property double z\nproperty uchar red\nelement face 1\nproperty uchar flags\nproperty list ushort uint vertex_index\n\
        property float quality\nelement edge 1\nproperty int a\nproperty int b\nend_header\n\
        0 0 0 9\n1 0 0 9\n1 1 0 9\n0 1 0 9\n7 4 0 1 2 3 0.5\n0 1\n";

    #[test]
    fn ascii_with_extra_properties_and_elements_and_any_list_types() {
        let m = parse_ply(ASCII_QUAD.as_bytes(), Path::new("q.ply"), Coordinates::Finite).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
    }

    fn binary(big: bool) -> Vec<u8> {
        let format = if big { "binary_big_endian" } else { "binary_little_endian" };
        let mut b = format!(
            "ply\nformat {format} 1.0\nelement vertex 3\nproperty short x\nproperty double y\nproperty float z\n\
             element face 1\nproperty int material\nproperty list uint short vertex_indices\nend_header\n"
        )
        .into_bytes();
        let put = |bytes: &mut Vec<u8>, mut v: Vec<u8>| {
            if big {
                v.reverse();
            }
            bytes.extend(v);
        };
        for (x, y, z) in [(0i16, 0.0f64, 0.0f32), (2, 0.0, 0.0), (0, 3.0, 0.5)] {
            put(&mut b, x.to_le_bytes().to_vec());
            put(&mut b, y.to_le_bytes().to_vec());
            put(&mut b, z.to_le_bytes().to_vec());
        }
        put(&mut b, 77i32.to_le_bytes().to_vec());
        put(&mut b, 3u32.to_le_bytes().to_vec());
        for i in [0i16, 1, 2] {
            put(&mut b, i.to_le_bytes().to_vec());
        }
        b
    }

    #[test]
    fn binary_both_endians_and_odd_types() {
        for big in [false, true] {
            let m = parse_ply(&binary(big), Path::new("b.ply"), Coordinates::Finite).unwrap();
            assert_eq!(m.positions, vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.5)], "big {big}");
            assert_eq!(m.triangles, vec![[0, 1, 2]]);
        }
    }

    #[test]
    fn faults_name_the_line_or_byte() {
        let p = Path::new("f.ply");
        let e = parse_ply(ASCII_QUAD.replace("1 1 0 9", "1 x 0 9").as_bytes(), p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.starts_with("f.ply:19:") && e.contains("'x'"), "{e}");
        let e = parse_ply(ASCII_QUAD.replace("7 4 0 1 2 3", "7 4 0 1 2 9").as_bytes(), p, Coordinates::Finite)
            .unwrap_err()
            .to_string();
        assert!(e.contains("refers to vertex 9"), "{e}");
        let e = parse_ply(
            ASCII_QUAD.replace("property uchar red\n", "property uchar red\nbogus\n").as_bytes(),
            p,
            Coordinates::Finite,
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("f.ply:9:") && e.contains("bogus"), "{e}");
        let full = binary(false);
        let e = parse_ply(&full[..full.len() - 1], p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.contains("face 0") && e.contains("ends early") && e.contains("byte"), "{e}");
        let e = parse_ply(b"\x00\x01binary garbage", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.contains("not a PLY file"), "{e}");
        let e = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 0\nelement face 0\nend_header\n", p, Coordinates::Finite);
        assert!(matches!(e, Err(IoError::Empty { .. })));
        let e = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", p, Coordinates::Finite)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no scalar x, y and z"), "{e}");
    }

    #[test]
    fn a_huge_declared_count_fails_without_allocating_it() {
        let b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\n\
                  property float z\nend_header\n\0\0\0\0";
        let e = parse_ply(b, Path::new("h.ply"), Coordinates::Any).unwrap_err().to_string();
        assert!(e.contains("ends early"), "{e}");
    }
}
