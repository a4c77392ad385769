//! What `-f SPEC` names, loaded: a built-in field, a mesh file (OBJ, PLY, STL, glTF) as a
//! signed-distance field, or a volume file (NIfTI, NRRD, MetaImage, isolab's raw grid, a zarr
//! store), with
//! the warnings a user should see about it.
//!
//! Mesh inputs are checked as they come in: a mesh wound inward as a whole is flipped
//! ([`MeshField`] takes `|winding number|`, so the field is the same either way), and open,
//! non-manifold, inconsistently wound and self-intersecting inputs are named in warnings (the
//! field still has an inside: the generalized winding number decides it).

use crate::error::RunError;
use crate::files::{read_file, FileContents};
use isolab_algorithms::fields::{self, MeshField, Volume, VolumeField};
use isolab_algorithms::{Field, TriMesh};
use isolab_io::volume::{self, Inside, VolumeFile, VolumeOptions};
use isolab_io::Coordinates;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What kind of input a run meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum InputKind {
    /// A built-in field.
    Builtin,
    /// A mesh file as a signed-distance field.
    Mesh,
    /// A volume file.
    Volume,
    /// An array handed over in memory (the Python package's numpy arrays).
    Array,
}

/// An input, loaded.
pub struct Input {
    /// The field in world coordinates (a [`VolumeField`] for volumes).
    pub field: Arc<dyn Field>,
    /// Kind of input.
    pub kind: InputKind,
    /// The volume, for volume files.
    pub volume: Option<Arc<VolumeFile>>,
    /// The mesh file's format ("PLY", ...), for mesh inputs.
    pub mesh_format: Option<&'static str>,
    /// What the user should know about the input (an inward mesh flipped, holes, ...).
    pub warnings: Vec<String>,
    /// Wall time reading, parsing and checking the file.
    pub read_time: Duration,
}

impl Input {
    /// A volume already in memory (values `i + ni * (j + nj * k)`, checked by [`Volume::new`]),
    /// as an input: `format` and `data_type` name where it came from (`"numpy"`, `"uint8"`), and
    /// `inside` is the side meshed as inside unless the run says otherwise.
    pub fn from_volume(volume: Volume, format: &'static str, data_type: &'static str, inside: Inside) -> Input {
        let volume = Arc::new(volume);
        let file = VolumeFile {
            volume: volume.clone(),
            format,
            data_type,
            space: volume::Space::Unknown,
            inside,
            iso: None,
            centres: None,
            notes: Vec::new(),
        };
        Input {
            field: Arc::new(VolumeField::new(volume)),
            kind: InputKind::Array,
            volume: Some(Arc::new(file)),
            mesh_format: None,
            warnings: Vec::new(),
            read_time: Duration::ZERO,
        }
    }

    /// Which side is inside unless the user says: the volume file's own, below otherwise.
    pub fn default_inside(&self) -> Inside {
        self.volume.as_ref().map_or(Inside::Below, |v| v.inside)
    }
}

/// Whether to check a mesh input's topology and self-intersections (warnings cost a pass over
/// the mesh; experiments that load the shipped models many times skip them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshChecks {
    /// Orientation, topology and self-intersections, as warnings.
    Warn,
    /// Only what the field needs (orientation).
    Skip,
}

/// Whether `spec` names a file rather than a built-in field.
pub fn is_file_spec(spec: &str) -> bool {
    let lower = spec.to_ascii_lowercase();
    let known = [".obj", ".ply", ".stl", ".glb", ".gltf", ".nii", ".nii.gz", ".nrrd", ".nhdr", ".mhd", ".mha", ".raw", ".zarr"];
    known.iter().any(|e| lower.trim_end_matches('/').ends_with(e))
        || spec.contains('/')
        || Path::new(spec).is_file()
        || volume::zarr::is_zarr(Path::new(spec))
}

/// Loads a built-in field by name, or a mesh or volume file.
pub fn load_input(spec: &str, seed: i32, volume_options: VolumeOptions, checks: MeshChecks) -> Result<Input, RunError> {
    let start = Instant::now();
    if !is_file_spec(spec) {
        let field = fields::builtin(spec, fields::FieldParams { seed })?;
        return Ok(Input {
            field,
            kind: InputKind::Builtin,
            volume: None,
            mesh_format: None,
            warnings: Vec::new(),
            read_time: start.elapsed(),
        });
    }
    let path = Path::new(spec);
    let (mesh, format) = match read_file(path, volume_options, Coordinates::Finite)? {
        FileContents::Volume(file) => {
            let file = Arc::new(file);
            return Ok(Input {
                field: Arc::new(VolumeField::new(file.volume.clone())),
                kind: InputKind::Volume,
                volume: Some(file),
                mesh_format: None,
                warnings: Vec::new(),
                read_time: start.elapsed(),
            });
        }
        FileContents::Mesh(mesh, format) => (mesh, format),
    };
    let name = volume::stem(path);
    let field = MeshField::new(name.clone(), &mesh.positions, &mesh.triangles)?;
    let mut warnings = Vec::new();
    if field.reoriented() {
        warnings.push(format!(
            "input mesh '{name}' faces inward as a whole (negative signed volume): its triangles were flipped; the inside is \
             the same either way (|winding number|)"
        ));
    }
    if checks == MeshChecks::Warn {
        warnings.extend(mesh_warnings(&name, &mesh));
    }
    Ok(Input {
        field: Arc::new(field),
        kind: InputKind::Mesh,
        volume: None,
        mesh_format: Some(format.name()),
        warnings,
        read_time: start.elapsed(),
    })
}

/// Warnings about a mesh used as a field: holes, non-manifold edges and vertices, inconsistent
/// winding, self-intersections.
pub fn mesh_warnings(name: &str, mesh: &TriMesh) -> Vec<String> {
    let t = isolab_metrics::topology(mesh);
    let mut warnings = Vec::new();
    if t.boundary_edges > 0 {
        warnings.push(format!(
            "input mesh '{name}' is open ({} boundary edges in {} holes): the generalized winding number closes it",
            t.boundary_edges, t.boundary_loops
        ));
    }
    if t.non_manifold_edges > 0 || t.non_manifold_vertices > 0 {
        warnings.push(format!(
            "input mesh '{name}' is not manifold ({} edges with more than two triangles, {} vertices whose triangles form \
             more than one fan)",
            t.non_manifold_edges, t.non_manifold_vertices
        ));
    }
    if t.misoriented_edges > 0 {
        warnings.push(format!(
            "input mesh '{name}' is not consistently wound ({} edges used twice in the same direction): the inside may be \
             wrong near them",
            t.misoriented_edges
        ));
    }
    let s = isolab_metrics::self_intersections(mesh);
    if s.count > 0 {
        warnings.push(format!(
            "input mesh '{name}' intersects itself ({} triangle pairs): the inside is decided by the winding number there",
            s.count
        ));
    }
    warnings
}

/// Loads a built-in field by name, or a mesh or volume file as a field in world coordinates
/// (no input checks): what experiments and tests sample.
pub fn load_field(spec: &str, seed: i32) -> Result<Arc<dyn Field>, RunError> {
    Ok(load_input(spec, seed, VolumeOptions::default(), MeshChecks::Skip)?.field)
}
