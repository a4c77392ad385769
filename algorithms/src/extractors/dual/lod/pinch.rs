//! The repair of a seam where a fine cell's ring meets a coarse cell's ([`pinch`]): the octree
//! rule's polygons can give such an edge four triangles, which the engine's ring rule prevents
//! between cells of one size only.

use crate::mesh::TriMesh;
use glam::Vec3;

/// Repairs the seams' rare non-manifold spots and returns how many vertices it added. A piece that
/// passes twice through one face square is a ring there; the engine joins a face two rings share
/// so that no edge across it gets four triangles, but a coarse cell and a fine one on a seam
/// share no such rule. So where a seam edge has four triangles, the vertex of the coarser cell is
/// pinched at the edge's other end `u` (its triangles, in order around it, pass `u` twice: the run
/// from `u` back to `u` gets a vertex of its own), and then each vertex involved whose triangles
/// form several fans gets a vertex per fan. Each copy moves half way toward the mean of its own
/// neighbours (kept in its cell), so the fans meet at no point; net sides follow the copies.
pub(super) fn pinch(
    mesh: &mut TriMesh,
    corners: &mut Vec<[u32; 3]>,
    seam_triangles: &[u32],
    side_of: impl Fn([u32; 3]) -> u32,
    links: &mut [(u32, u32)],
    keep_links: bool,
) -> usize {
    let mut uses: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for &t in seam_triangles {
        let t = mesh.triangles[t as usize];
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut crowded: Vec<(u32, u32)> = uses.into_iter().filter(|&(_, n)| n > 2).map(|(e, _)| e).collect();
    if crowded.is_empty() {
        return 0;
    }
    crowded.sort_unstable();
    let before = mesh.positions.len();
    // Each copy's original.
    let mut original: Vec<u32> = Vec::new();
    let mut touched = Vec::new();
    for (a, b) in crowded {
        let (sa, sb) = (side_of(corners[a as usize]), side_of(corners[b as usize]));
        let (v, u) = if (sa, a) > (sb, b) { (a, b) } else { (b, a) };
        touched.extend([v, u]);
        while let Some(run) = run_through(mesh, v, u) {
            let copy = detach(mesh, corners, v, &run);
            original.push(v);
            touched.push(copy);
        }
    }
    touched.sort_unstable();
    touched.dedup();
    for v in touched {
        let fans = fans(mesh, v);
        for fan in fans.iter().skip(1) {
            detach(mesh, corners, v, fan);
            original.push(v);
        }
    }
    // Each copy, and its original, half way toward its own neighbours' mean, in its cell.
    let family = |w: u32| if (w as usize) < before { w } else { original[w as usize - before] };
    let mut moved: Vec<u32> = original.clone();
    moved.extend((before..mesh.positions.len()).map(|w| w as u32));
    moved.sort_unstable();
    moved.dedup();
    let targets: Vec<(u32, Vec3)> = moved
        .iter()
        .map(|&w| {
            let around: Vec<Vec3> =
                star(mesh, w).iter().map(|&t| mesh.positions[link_edge(mesh.triangles[t], w).0 as usize]).collect();
            let mean = around.iter().sum::<Vec3>() / around.len().max(1) as f32;
            let p = mesh.positions[w as usize];
            let lo = Vec3::from(corners[w as usize].map(|c| c as f32));
            let side = side_of(corners[w as usize]) as f32;
            (w, (p + 0.5 * (mean - p)).clamp(lo, lo + Vec3::splat(side)))
        })
        .collect();
    for (w, p) in targets {
        mesh.positions[w as usize] = p;
    }
    if keep_links {
        // A net side from a split vertex goes to the member of its family beside the other end.
        let members = |w: u32| {
            let root = family(w);
            std::iter::once(root).chain((before..mesh.positions.len()).map(|c| c as u32).filter(move |&c| family(c) == root))
        };
        for side in links.iter_mut() {
            let (a, b) = *side;
            let split = |w: u32| original.contains(&family(w));
            if split(a) {
                if let Some(m) = members(a).find(|&m| shares_triangle(mesh, m, b)) {
                    side.0 = m;
                }
            }
            if split(b) {
                if let Some(m) = members(b).find(|&m| shares_triangle(mesh, side.0, m)) {
                    side.1 = m;
                }
            }
        }
    }
    mesh.positions.len() - before
}

/// The triangles around `v`.
fn star(mesh: &TriMesh, v: u32) -> Vec<usize> {
    (0..mesh.triangles.len()).filter(|&t| mesh.triangles[t].contains(&v)).collect()
}

/// Whether some triangle has both `a` and `b`.
fn shares_triangle(mesh: &TriMesh, a: u32, b: u32) -> bool {
    mesh.triangles.iter().any(|t| t.contains(&a) && t.contains(&b))
}

/// The link edge of triangle `t` seen from its vertex `v`: the two others in winding order.
fn link_edge(t: [u32; 3], v: u32) -> (u32, u32) {
    let k = t.iter().position(|&x| x == v).expect("v is a corner");
    (t[(k + 1) % 3], t[(k + 2) % 3])
}

/// When `v`'s triangles pass `u` twice, those of the run from `u` back to `u` (fewer than all).
fn run_through(mesh: &TriMesh, v: u32, u: u32) -> Option<Vec<usize>> {
    let star = star(mesh, v);
    if star.iter().filter(|&&t| link_edge(mesh.triangles[t], v).0 == u).count() < 2 {
        return None;
    }
    let mut run: Vec<usize> = Vec::new();
    let mut at = u;
    loop {
        let &t = star.iter().find(|&&t| link_edge(mesh.triangles[t], v).0 == at && !run.contains(&t))?;
        run.push(t);
        at = link_edge(mesh.triangles[t], v).1;
        if at == u {
            break;
        }
    }
    (run.len() < star.len()).then_some(run)
}

/// `v`'s triangles grouped into fans (each a run of triangles sharing edges around `v`).
fn fans(mesh: &TriMesh, v: u32) -> Vec<Vec<usize>> {
    let star = star(mesh, v);
    let mut left = star.clone();
    let mut out = Vec::new();
    while let Some(first) = left.pop() {
        let mut fan = vec![first];
        let mut grew = true;
        while grew {
            grew = false;
            left.retain(|&t| {
                let (a, b) = link_edge(mesh.triangles[t], v);
                let joins = fan.iter().any(|&f| {
                    let (c, d) = link_edge(mesh.triangles[f], v);
                    a == d || b == c || a == c || b == d
                });
                if joins {
                    fan.push(t);
                    grew = true;
                }
                !joins
            });
        }
        out.push(fan);
    }
    out
}

/// A copy of `v` (same position and cell) that takes `v`'s place in `triangles`.
fn detach(mesh: &mut TriMesh, corners: &mut Vec<[u32; 3]>, v: u32, triangles: &[usize]) -> u32 {
    let copy = mesh.positions.len() as u32;
    mesh.positions.push(mesh.positions[v as usize]);
    corners.push(corners[v as usize]);
    for &t in triangles {
        for x in mesh.triangles[t].iter_mut().filter(|x| **x == v) {
            *x = copy;
        }
    }
    copy
}
