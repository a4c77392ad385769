//! Every file reader on mutated and random bytes: an error naming the file, never a panic.
//!
//! Seeds are real files of every format we read (meshes isolab writes in each format, the
//! committed volume fixtures); proptest flips, overwrites, inserts and truncates bytes.

use isolab_algorithms::fields::Volume;
use isolab_io::volume::{metaimage, nifti, nrrd, VolumeOptions};
use isolab_io::{self as io, Coordinates, IoError};
use proptest::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// One seed file: a name (its extension picks the reader) and its bytes.
struct Seed {
    name: &'static str,
    bytes: Vec<u8>,
}

fn seeds() -> &'static [Seed] {
    static SEEDS: OnceLock<Vec<Seed>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let mesh = isolab_algorithms::TriMesh::unit_tetrahedron();
        let dir = std::env::temp_dir().join(format!("isolab-parsers-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut out = Vec::new();
        for name in ["t.obj", "t.ply", "t.stl", "t.glb", "t.gltf"] {
            let path = dir.join(name);
            let colours = [[1, 2, 3], [4, 5, 6], [7, 8, 9], [10, 11, 12]];
            io::write_mesh_with(&path, &mesh, io::MeshExtras { colours: Some(&colours), space: None }).unwrap();
            out.push(Seed { name, bytes: std::fs::read(&path).unwrap() });
        }
        let mut ascii_ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                              element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
            .to_vec();
        out.push(Seed { name: "a.ply", bytes: std::mem::take(&mut ascii_ply) });
        out.push(Seed {
            name: "a.stl",
            bytes: b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n".to_vec(),
        });
        let volumes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/volumes");
        for name in ["mni-small.nii.gz", "mni-small-qform.nii", "mni-small-2.nii.gz", "mni-small.nrrd", "mni-small.nhdr", "mni-small.mhd"] {
            out.push(Seed { name, bytes: std::fs::read(volumes.join(name)).unwrap() });
        }
        let _ = std::fs::remove_dir_all(&dir);
        out
    })
}

/// Parses `bytes` as the format `name` says; detached data files come from the fixtures.
fn parse(name: &str, bytes: &[u8]) -> Result<(), IoError> {
    let path = Path::new(name);
    let no_files = |file: &str| -> Result<Vec<u8>, IoError> {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/volumes");
        match file {
            "mni-small.raw" | "mni-small.zraw" => Ok(std::fs::read(fixtures.join(file)).unwrap()),
            _ => Err(IoError::Read { path: file.into(), source: std::io::Error::from(std::io::ErrorKind::NotFound) }),
        }
    };
    let check = |v: &Volume| assert!(v.values_f32().iter().all(|x| x.is_finite()));
    if name.ends_with(".nii") || name.ends_with(".nii.gz") {
        nifti::parse_nifti(bytes, path, VolumeOptions::default(), &no_files).map(|f| check(&f.volume))
    } else if name.ends_with(".nrrd") || name.ends_with(".nhdr") {
        nrrd::parse_nrrd(bytes, path, VolumeOptions::default(), &no_files).map(|f| check(&f.volume))
    } else if name.ends_with(".mhd") {
        metaimage::parse_metaimage(bytes, path, VolumeOptions::default(), &no_files).map(|f| check(&f.volume))
    } else {
        io::parse_mesh(bytes, path, Coordinates::Any).map(|_| ())
    }
}

fn assert_named(name: &str, result: Result<(), IoError>) {
    if let Err(e) = result {
        let message = e.to_string();
        let file = Path::new(name).file_name().unwrap().to_string_lossy().into_owned();
        // A detached header's fault may lie in its data file, which the message names instead.
        let names_it = message.contains(&file)
            || message.contains("mni-small.raw")
            || message.contains("mni-small.zraw")
            || matches!(e, IoError::Read { .. });
        assert!(names_it, "{name}: the error does not name the file: {message}");
    }
}

/// Byte edits: (position fraction, new byte) pairs, an optional insertion (position fraction,
/// bytes), and the fraction of the file kept.
type Edits = (Vec<(f64, u8)>, Option<(f64, Vec<u8>)>, f64);

fn edits() -> impl Strategy<Value = Edits> {
    (
        prop::collection::vec((0.0..1.0f64, any::<u8>()), 0..8),
        prop::option::of((0.0..1.0f64, prop::collection::vec(any::<u8>(), 1..16))),
        prop_oneof![Just(1.0), 0.0..1.0f64],
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_give_errors_naming_the_file_never_panics(seed in 0..13usize, (changes, insert, keep) in edits()) {
        let s = &seeds()[seed % seeds().len()];
        // Mutate the decompressed content of gzip seeds too, not only their compressed bytes.
        let mut bytes = s.bytes.clone();
        for (at, b) in &changes {
            let i = ((bytes.len() as f64) * at) as usize;
            if i < bytes.len() {
                bytes[i] = *b;
            }
        }
        if let Some((at, extra)) = &insert {
            let i = ((bytes.len() as f64) * at) as usize;
            bytes.splice(i.min(bytes.len())..i.min(bytes.len()), extra.iter().copied());
        }
        bytes.truncate(((bytes.len() as f64) * keep).ceil() as usize);
        assert_named(s.name, parse(s.name, &bytes));
    }

    #[test]
    fn random_bytes_give_errors_naming_the_file_never_panics(seed in 0..13usize, bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let s = &seeds()[seed % seeds().len()];
        assert_named(s.name, parse(s.name, &bytes));
    }
}

#[test]
fn every_seed_parses_unmutated() {
    assert_eq!(seeds().len(), 13);
    for s in seeds() {
        parse(s.name, &s.bytes).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    }
}

/// Inputs the fuzzers (`fuzz/`) found, one numbered file each in `tests/fuzz-regressions/`.
#[test]
fn fuzz_regression_0001_a_glb_with_a_non_finite_position_is_refused_as_a_field() {
    // mesh_detect found it: glTF positions skipped the finiteness check OBJ, PLY and STL make, so
    // a GLB with a NaN vertex was accepted as a field.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz-regressions/0001-mesh_detect-glb-nan-position.glb");
    let bytes = std::fs::read(&path).unwrap();
    let err = io::parse_mesh(&bytes, &path, Coordinates::Finite).expect_err("a non-finite vertex is refused");
    assert!(err.to_string().contains("0001-mesh_detect") && err.to_string().contains("not finite"), "{err}");
    // Measuring still reads it (and counts the vertex), as for the other formats.
    let mesh = io::parse_mesh(&bytes, &path, Coordinates::Any).unwrap();
    assert!(mesh.positions.iter().any(|p| !p.is_finite()));
}

#[test]
fn fuzz_regression_0002_a_short_gzip_stream_gets_no_more_memory_than_it_can_fill() {
    // nifti found it: a 5 KB .nii.gz whose header claims about 4 GB of voxels made the reader
    // reserve all of it before decompressing. The file is refused, and a claim of a terabyte
    // from a few bytes ends with "decompresses to only", not with an allocation of a terabyte.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz-regressions/0002-nifti-gzip-header-claims-4gb.nii.gz");
    let bytes = std::fs::read(&path).unwrap();
    let none = |_: &str| -> Result<Vec<u8>, IoError> { Err(IoError::Invalid { path: "none".into(), reason: "none".into() }) };
    let err = nifti::parse_nifti(&bytes, &path, VolumeOptions::default(), &none).expect_err("refused");
    assert!(err.to_string().contains("0002-nifti"), "{err}");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    std::io::Write::write_all(&mut gz, &[7u8; 100]).unwrap();
    let small = gz.finish().unwrap();
    let err = isolab_io::volume::inflate(&small, isolab_io::volume::Compression::Gzip, 1 << 40, &path)
        .expect_err("a terabyte is not in 100 bytes");
    assert!(err.to_string().contains("decompresses to only 100"), "{err}");
}
