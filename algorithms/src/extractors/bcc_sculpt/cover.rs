//! The snowflake choice: one vertex per bomb minimising the missing tetrahedra restored, solved
//! exactly by branch and bound per group of interacting bombs (capped at
//! [`super::COVER_NODE_LIMIT`] nodes), seeded with a greedy cover.

use super::lattice::BccLattice;
use std::collections::HashMap;

/// Groups of bombs (indices into `candidates`) whose candidate snowflakes share a vertex or a
/// missing tetrahedron; groups are independent of each other.
pub(super) fn interacting_groups(lattice: &BccLattice, keep: &[bool], candidates: &[Vec<u32>]) -> Vec<Vec<usize>> {
    let mut sets = petgraph::unionfind::UnionFind::<usize>::new(candidates.len());
    let mut owner: HashMap<u64, usize> = HashMap::new();
    for (i, c) in candidates.iter().enumerate() {
        for &v in c {
            let keys = std::iter::once(u64::from(v) | 1 << 63)
                .chain(lattice.star(v).iter().filter(|&&t| !keep[t as usize]).map(|&t| u64::from(t)));
            for key in keys {
                match owner.get(&key) {
                    Some(&j) => {
                        sets.union(i, j);
                    }
                    None => {
                        owner.insert(key, i);
                    }
                }
            }
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for i in 0..candidates.len() {
        let root = sets.find_mut(i);
        groups.entry(root).or_default().push(i);
    }
    let mut groups: Vec<Vec<usize>> = groups.into_values().collect();
    groups.sort();
    groups
}

/// Choose one vertex per bomb minimising the number of distinct missing tetrahedra in the chosen
/// vertices' snowflakes. Vertices and tetrahedra are renumbered locally.
pub(super) struct CoverProblem {
    /// Global id of each local vertex.
    pub(super) vertices: Vec<u32>,
    /// Missing tetrahedra (local ids) of each local vertex's snowflake.
    pub(super) cost: Vec<Vec<u32>>,
    /// Candidate local vertices of each bomb.
    pub(super) bombs: Vec<Vec<u32>>,
    /// Local tetrahedra.
    pub(super) tets: usize,
}

impl CoverProblem {
    pub(super) fn new<'a>(lattice: &BccLattice, keep: &[bool], bombs: impl Iterator<Item = &'a [u32]>) -> Self {
        let mut vertex_id: HashMap<u32, u32> = HashMap::new();
        let mut tet_id: HashMap<u32, u32> = HashMap::new();
        let mut vertices = Vec::new();
        let mut cost = Vec::new();
        let bombs = bombs
            .map(|c| {
                c.iter()
                    .map(|&v| {
                        *vertex_id.entry(v).or_insert_with(|| {
                            vertices.push(v);
                            let missing = lattice.star(v).iter().filter(|&&t| !keep[t as usize]);
                            cost.push(
                                missing
                                    .map(|&t| {
                                        let next = tet_id.len() as u32;
                                        *tet_id.entry(t).or_insert(next)
                                    })
                                    .collect(),
                            );
                            vertices.len() as u32 - 1
                        })
                    })
                    .collect()
            })
            .collect();
        Self { vertices, cost, bombs, tets: tet_id.len() }
    }

    /// The chosen vertices (global ids) and whether the search finished within `node_limit`.
    pub(super) fn solve(&self, node_limit: usize) -> (Vec<u32>, bool) {
        let greedy = self.greedy();
        let mut search = Search {
            problem: self,
            count: vec![0; self.tets],
            cost: 0,
            chosen: vec![false; self.vertices.len()],
            best_cost: self.cover_cost(&greedy),
            best: greedy,
            nodes: 0,
            limit: node_limit,
        };
        search.descend(0);
        let exhaustive = search.nodes <= node_limit;
        let chosen = search.best.iter().enumerate().filter(|(_, &c)| c).map(|(v, _)| self.vertices[v]).collect();
        (chosen, exhaustive)
    }

    /// Repeatedly picks the vertex covering the most uncovered bombs per added tetrahedron.
    pub(super) fn greedy(&self) -> Vec<bool> {
        let mut chosen = vec![false; self.vertices.len()];
        let mut added = vec![false; self.tets];
        loop {
            let uncovered: Vec<&Vec<u32>> = self.bombs.iter().filter(|c| !c.iter().any(|&v| chosen[v as usize])).collect();
            if uncovered.is_empty() {
                return chosen;
            }
            let score = |v: u32| {
                let covers = uncovered.iter().filter(|c| c.contains(&v)).count() as f64;
                let new = self.cost[v as usize].iter().filter(|&&t| !added[t as usize]).count() as f64;
                covers / (1.0 + new)
            };
            let best = uncovered
                .iter()
                .flat_map(|c| c.iter().copied())
                .max_by(|&a, &b| score(a).total_cmp(&score(b)).then(b.cmp(&a)))
                .expect("bombs have candidates");
            chosen[best as usize] = true;
            self.cost[best as usize].iter().for_each(|&t| added[t as usize] = true);
        }
    }

    pub(super) fn cover_cost(&self, chosen: &[bool]) -> usize {
        let mut added = vec![false; self.tets];
        for (v, _) in chosen.iter().enumerate().filter(|(_, &c)| c) {
            self.cost[v].iter().for_each(|&t| added[t as usize] = true);
        }
        added.iter().filter(|&&a| a).count()
    }
}

/// Depth-first branch and bound over the bombs in order.
pub(super) struct Search<'a> {
    pub(super) problem: &'a CoverProblem,
    pub(super) count: Vec<u32>,
    pub(super) cost: usize,
    pub(super) chosen: Vec<bool>,
    pub(super) best: Vec<bool>,
    pub(super) best_cost: usize,
    pub(super) nodes: usize,
    pub(super) limit: usize,
}

impl Search<'_> {
    pub(super) fn descend(&mut self, bomb: usize) {
        self.nodes += 1;
        if self.nodes > self.limit || self.cost >= self.best_cost {
            return;
        }
        let Some(candidates) = self.problem.bombs.get(bomb) else {
            self.best_cost = self.cost;
            self.best.clone_from(&self.chosen);
            return;
        };
        if candidates.iter().any(|&v| self.chosen[v as usize]) {
            return self.descend(bomb + 1);
        }
        for &v in candidates {
            self.choose(v, true);
            self.descend(bomb + 1);
            self.choose(v, false);
        }
    }

    pub(super) fn choose(&mut self, v: u32, on: bool) {
        self.chosen[v as usize] = on;
        for &t in &self.problem.cost[v as usize] {
            let c = &mut self.count[t as usize];
            if on {
                *c += 1;
                self.cost += usize::from(*c == 1);
            } else {
                *c -= 1;
                self.cost -= usize::from(*c == 0);
            }
        }
    }
}
