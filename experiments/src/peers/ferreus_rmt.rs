//! The `ferreus_rmt` crate (Maptek, MIT): an independent regularised marching tetrahedra that
//! follows the surface from seed points instead of sampling the whole volume. It evaluates the
//! field itself (in batches; we evaluate each batch in parallel, as our own sampling is), so its
//! time is comparable with our sampling plus extraction. It keeps no state between calls, so its
//! steady state is its one-shot run.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use glam::Vec3;
use isolab_algorithms::geometry::Aabb;
use isolab_algorithms::{Field, TriMesh};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// One `ferreus_rmt` run.
struct FerreusRun {
    /// Its mesh (wound like ours: counter-clockwise seen from outside).
    mesh: TriMesh,
    /// Wall time of `build_isosurface`, field evaluations included.
    time: Duration,
    /// Field evaluations it asked for.
    evaluations: usize,
    /// Whether its triangles came wound the other way and were flipped to compare.
    flipped: bool,
}

/// Runs `ferreus_rmt::build_isosurface` with its plain averaging clustering (the paper's) on
/// `field` over `domain` at lattice spacing `spacing`, seeded at `seeds`, leaving the surface open
/// at the domain boundary.
fn ferreus_rmt(field: &dyn Field, domain: &Aabb, spacing: f32, iso: f32, seeds: &[Vec3]) -> FerreusRun {
    use faer::{Mat, MatRef};
    let evaluations = AtomicUsize::new(0);
    let mut f = |pts: MatRef<'_, f64>| -> Mat<f64> {
        let n = pts.nrows();
        evaluations.fetch_add(n, Ordering::Relaxed);
        let points: Vec<Vec3> = (0..n).map(|r| Vec3::new(pts[(r, 0)] as f32, pts[(r, 1)] as f32, pts[(r, 2)] as f32)).collect();
        let values: Vec<f64> = points.par_iter().map(|&p| f64::from(field.value(p))).collect();
        Mat::from_fn(n, 1, |r, _| values[r])
    };
    let seeds = Mat::from_fn(seeds.len(), 3, |r, c| f64::from(seeds[r][c]));
    let extents = [domain.min.x, domain.min.y, domain.min.z, domain.max.x, domain.max.y, domain.max.z].map(f64::from);
    let t = Instant::now();
    let mesh = ferreus_rmt::build_isosurface(
        seeds.as_ref(),
        &extents,
        f64::from(spacing),
        f64::from(iso),
        &mut f,
        None,
        ferreus_rmt::ClusterMethod::Average,
        ferreus_rmt::BoundaryClosure::None,
        None,
    );
    let time = t.elapsed();
    let positions: Vec<Vec3> = (0..mesh.vertices.nrows())
        .map(|r| Vec3::new(mesh.vertices[(r, 0)] as f32, mesh.vertices[(r, 1)] as f32, mesh.vertices[(r, 2)] as f32))
        .collect();
    let mut triangles: Vec<[u32; 3]> = (0..mesh.facets.nrows())
        .map(|r| [mesh.facets[(r, 0)] as u32, mesh.facets[(r, 1)] as u32, mesh.facets[(r, 2)] as u32])
        .collect();
    let mut out = TriMesh { positions, normals: Vec::new(), triangles: Vec::new() };
    out.triangles.clone_from(&triangles);
    let flipped = isolab_metrics::signed_volume(&out) < 0.0;
    if flipped {
        for t in &mut triangles {
            t.swap(1, 2);
        }
        out.triangles = triangles;
    }
    out.compute_face_weighted_normals();
    FerreusRun { mesh: out, time, evaluations: evaluations.into_inner(), flipped }
}

/// The `ferreus_rmt` peer (jobs: [`Job::Field`]).
pub struct FerreusRmt;

impl Peer for FerreusRmt {
    fn name(&self) -> String {
        "ferreus_rmt".into()
    }

    fn run(&mut self, job: &Job<'_>, _: Protocol) -> Result<PeerRun, PeerError> {
        let Job::Field { field, domain, spacing, iso, seeds } = job else { return Err(self.unsupported()) };
        let run = ferreus_rmt(*field, domain, *spacing, *iso, seeds);
        Ok(PeerRun {
            time: run.time,
            vertices: run.mesh.positions.len(),
            triangles: run.mesh.triangles.len(),
            mesh: Some(run.mesh),
            evaluations: Some(run.evaluations),
            flipped: run.flipped,
        })
    }
}
