//! One level of the lifting transform: topology set-up, analysis, synthesis, statistics.

use nalgebra::{Point3, Vector3};

use super::WaveletError;
use super::kdisk::KDiskUpdate;
use crate::multires::{Creases, Split};

/// Coordinate vectors of a level's vertices (or its details).
pub(super) type Coords = Vec<Vector3<f64>>;

/// Loop's total ring weight `a(n) = 5/8 − (3 + 2cos(2π/n))²/64` of a smooth vertex of
/// valence `n` (its neighbours get `β = a(n)/n` each, itself `1 − a(n)`).
pub fn loop_ring_weight(n: usize) -> f64 {
    let t = 3.0 + 2.0 * (2.0 * std::f64::consts::PI / n as f64).cos();
    5.0 / 8.0 - t * t / 64.0
}

/// Class of a coarse vertex, from its number of sharp (crease or boundary) edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VertexClass {
    /// No sharp edge: Loop's smooth vertex rule.
    Smooth,
    /// Exactly two sharp edges: the crease/boundary rule.
    Crease,
    /// One or at least three sharp edges, or no edge at all: the vertex stays.
    Corner,
}

/// Options of the transform. `Default` is the plain Loop lifting (no extra update).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WaveletOptions {
    /// Apply the extra k-disk least-squares lifting update (seed 004 eqs. 2.22–2.24) so the
    /// coarse positions approximate the fine surface better in the least-squares sense.
    /// Still exactly invertible; a pure Loop surface still has zero details. Default: off.
    pub kdisk_update: bool,
}

impl WaveletOptions {
    /// Sets [`WaveletOptions::kdisk_update`].
    pub fn with_kdisk_update(mut self, on: bool) -> Self {
        self.kdisk_update = on;
        self
    }
}

/// Loop's edge rule for one coarse edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum EdgeRule {
    /// Crease or boundary edge: midpoint.
    Sharp,
    /// Interior edge with its two opposite vertices: `(3a + 3b + p + q)/8`.
    Interior { opposite: [u32; 2] },
}

/// A coarse triangle recovered from the fine triangles of a [`Split`], with the indices of
/// its edges `ab`, `bc`, `ca`.
#[derive(Clone, Copy, Debug)]
pub(super) struct CoarseTriangle {
    pub vertices: [u32; 3],
    pub edges: [usize; 3],
}

fn invalid(reason: impl Into<String>) -> WaveletError {
    WaveletError::InvalidSplit {
        reason: reason.into(),
    }
}

/// Checks the 1-to-4 numbering contract of `split` and returns its coarse triangles.
pub(super) fn coarse_triangles(split: &Split) -> Result<Vec<CoarseTriangle>, WaveletError> {
    let v = split.coarse_vertices;
    let e = split.edges.len();
    if (v + e) > u32::MAX as usize {
        return Err(invalid("too many fine vertices for u32 indices"));
    }
    for (k, &[a, b]) in split.edges.iter().enumerate() {
        if a >= b || b as usize >= v {
            return Err(invalid(format!(
                "edge {k} = {:?} is not [min, max] < V",
                [a, b]
            )));
        }
        if k > 0 && split.edges[k - 1] >= [a, b] {
            return Err(invalid(format!("edges not strictly sorted at {k}")));
        }
    }
    if !split.triangles.len().is_multiple_of(4) {
        return Err(invalid("fine triangle count is not a multiple of 4"));
    }
    let odd_edge = |m: u32, x: u32, y: u32| -> Result<usize, WaveletError> {
        let m = m as usize;
        if m < v || m >= v + e {
            return Err(invalid(format!("fine vertex {m} should be an odd vertex")));
        }
        let k = m - v;
        if split.edges[k] != [x.min(y), x.max(y)] {
            return Err(invalid(format!(
                "odd vertex {m} is not on edge {:?}",
                [x, y]
            )));
        }
        Ok(k)
    };
    let mut out = Vec::with_capacity(split.triangles.len() / 4);
    for (t, quad) in split.triangles.chunks_exact(4).enumerate() {
        let [a, ab, ca] = quad[0];
        let [ab1, b, bc] = quad[1];
        let [ca1, bc1, c] = quad[2];
        if ab1 != ab || ca1 != ca || bc1 != bc || quad[3] != [ab, bc, ca] {
            return Err(invalid(format!(
                "fine triangles {}..{} break the pattern",
                4 * t,
                4 * t + 4
            )));
        }
        if a as usize >= v || b as usize >= v || c as usize >= v || a == b || b == c || c == a {
            return Err(invalid(format!(
                "coarse triangle {t} = {:?} is invalid",
                [a, b, c]
            )));
        }
        let edges = [
            odd_edge(ab, a, b)?,
            odd_edge(bc, b, c)?,
            odd_edge(ca, c, a)?,
        ];
        out.push(CoarseTriangle {
            vertices: [a, b, c],
            edges,
        });
    }
    Ok(out)
}

fn crease_index(split: &Split, edge: [u32; 2]) -> Result<usize, WaveletError> {
    let key = [edge[0].min(edge[1]), edge[0].max(edge[1])];
    split
        .edges
        .binary_search(&key)
        .map_err(|_| WaveletError::UnknownCreaseEdge { edge })
}

/// The creases of the fine level of `split`: crease edge `{a, b}` with odd vertex `m`
/// becomes `{a, m}` and `{m, b}` (boundary edges need no listing; they stay boundary).
pub fn refine_creases(split: &Split, creases: &Creases) -> Result<Creases, WaveletError> {
    let mut edges = Vec::with_capacity(2 * creases.edges.len());
    for &edge in &creases.edges {
        let k = crease_index(split, edge)?;
        let m = (split.coarse_vertices + k) as u32;
        let [a, b] = split.edges[k];
        edges.push([a, m]); // a < V <= m
        edges.push([b, m]);
    }
    edges.sort_unstable();
    edges.dedup();
    Ok(Creases { edges })
}

/// Everything the lifting steps need about one level, computed once from the [`Split`] and
/// the coarse [`Creases`] (connectivity only, no positions).
#[derive(Clone, Debug)]
pub struct LevelTopology {
    coarse_vertices: usize,
    edges: Vec<[u32; 2]>,
    edge_rules: Vec<EdgeRule>,
    classes: Vec<VertexClass>,
    /// Update step: `even_i = alpha_i c_i + gamma_i Σ_{k ∈ K_i} odd_k`.
    alpha: Vec<f64>,
    gamma: Vec<f64>,
    kdisk: Option<KDiskUpdate>,
}

impl LevelTopology {
    /// Validates `split` and `creases` and prepares the plain lifting transform.
    pub fn new(split: &Split, creases: &Creases) -> Result<Self, WaveletError> {
        Self::new_opt(split, creases, &WaveletOptions::default())
    }

    /// Like [`LevelTopology::new`], with options.
    pub fn new_opt(
        split: &Split,
        creases: &Creases,
        options: &WaveletOptions,
    ) -> Result<Self, WaveletError> {
        let v = split.coarse_vertices;
        let e = split.edges.len();
        let triangles = coarse_triangles(split)?;
        let mut count = vec![0usize; e];
        let mut opposite = vec![[0u32; 2]; e];
        for t in &triangles {
            let [a, b, c] = t.vertices;
            for (k, o) in t.edges.into_iter().zip([c, a, b]) {
                if count[k] < 2 {
                    opposite[k][count[k]] = o;
                }
                count[k] += 1;
            }
        }
        let mut sharp = vec![false; e];
        for k in 0..e {
            match count[k] {
                0 => return Err(invalid(format!("edge {k} has no triangle"))),
                1 => sharp[k] = true,
                2 => {}
                n => {
                    return Err(WaveletError::NonManifoldEdge {
                        edge: split.edges[k],
                        triangles: n,
                    });
                }
            }
        }
        for &edge in &creases.edges {
            sharp[crease_index(split, edge)?] = true;
        }
        let edge_rules: Vec<EdgeRule> = (0..e)
            .map(|k| {
                if sharp[k] {
                    EdgeRule::Sharp
                } else {
                    EdgeRule::Interior {
                        opposite: opposite[k],
                    }
                }
            })
            .collect();
        let mut valence = vec![0usize; v];
        let mut sharp_count = vec![0usize; v];
        for (k, &[a, b]) in split.edges.iter().enumerate() {
            valence[a as usize] += 1;
            valence[b as usize] += 1;
            if sharp[k] {
                sharp_count[a as usize] += 1;
                sharp_count[b as usize] += 1;
            }
        }
        let mut classes = Vec::with_capacity(v);
        let mut alpha = Vec::with_capacity(v);
        let mut gamma = Vec::with_capacity(v);
        for i in 0..v {
            let (class, al, ga) = match (sharp_count[i], valence[i]) {
                (_, 0) => (VertexClass::Corner, 1.0, 0.0),
                (0, n) => {
                    let a = loop_ring_weight(n);
                    (VertexClass::Smooth, 1.0 - 1.6 * a, 1.6 * a / n as f64)
                }
                (2, _) => (VertexClass::Crease, 0.5, 0.25),
                _ => (VertexClass::Corner, 1.0, 0.0),
            };
            classes.push(class);
            alpha.push(al);
            gamma.push(ga);
        }
        let mut level = LevelTopology {
            coarse_vertices: v,
            edges: split.edges.clone(),
            edge_rules,
            classes,
            alpha,
            gamma,
            kdisk: None,
        };
        if options.kdisk_update {
            level.kdisk = Some(KDiskUpdate::new(&level));
        }
        Ok(level)
    }

    /// Number of coarse (even) vertices `V_j`.
    pub fn coarse_vertices(&self) -> usize {
        self.coarse_vertices
    }

    /// Number of coarse edges, i.e. of details.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Number of fine vertices `V_j + |E_j|`.
    pub fn fine_vertices(&self) -> usize {
        self.coarse_vertices + self.edges.len()
    }

    /// Class of coarse vertex `i` (`None` if out of range).
    pub fn vertex_class(&self, i: usize) -> Option<VertexClass> {
        self.classes.get(i).copied()
    }

    /// Update weights `(α_i, γ_i)` of coarse vertex `i`: `even_i = α_i c_i + γ_i Σ odd_k`.
    pub fn update_weights(&self, i: usize) -> Option<(f64, f64)> {
        Some((*self.alpha.get(i)?, *self.gamma.get(i)?))
    }

    /// Whether the k-disk update is active.
    pub fn has_kdisk_update(&self) -> bool {
        self.kdisk.is_some()
    }

    /// `α_i` (i < V, unchecked).
    pub(super) fn alpha(&self, i: usize) -> f64 {
        self.alpha[i]
    }

    /// `γ_i` (i < V, unchecked).
    pub(super) fn gamma(&self, i: usize) -> f64 {
        self.gamma[i]
    }

    pub(super) fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    pub(super) fn edge_rule(&self, k: usize) -> EdgeRule {
        self.edge_rules[k]
    }

    /// Whether odd vertex `k` enters the update of its endpoint `i`.
    pub(super) fn contributes(&self, i: u32, k: usize) -> bool {
        match self.classes[i as usize] {
            VertexClass::Smooth => true,
            VertexClass::Crease => self.edge_rules[k] == EdgeRule::Sharp,
            VertexClass::Corner => false,
        }
    }

    /// Loop's edge rule on coarse positions `c` (all slices pre-validated).
    fn predict(&self, k: usize, c: &[Vector3<f64>]) -> Vector3<f64> {
        let [a, b] = self.edges[k];
        let (ca, cb) = (c[a as usize], c[b as usize]);
        match self.edge_rules[k] {
            EdgeRule::Sharp => (ca + cb) * 0.5,
            EdgeRule::Interior { opposite: [p, q] } => {
                (ca + cb) * 0.375 + (c[p as usize] + c[q as usize]) * 0.125
            }
        }
    }

    /// `Σ_{k ∈ K_i} odd_k` for every coarse vertex i.
    fn accumulate_odds(&self, odd: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut acc = vec![Vector3::zeros(); self.coarse_vertices];
        for (k, &[a, b]) in self.edges.iter().enumerate() {
            if self.contributes(a, k) {
                acc[a as usize] += odd[k];
            }
            if self.contributes(b, k) {
                acc[b as usize] += odd[k];
            }
        }
        acc
    }

    fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), WaveletError> {
        if expected == found {
            Ok(())
        } else {
            Err(WaveletError::LengthMismatch {
                what,
                expected,
                found,
            })
        }
    }

    /// Analysis on coordinate vectors: fine (length `V + E`) → (coarse, details).
    pub(super) fn analyse_coords(
        &self,
        fine: &[Vector3<f64>],
    ) -> Result<(Coords, Coords), WaveletError> {
        Self::check_len("fine positions", self.fine_vertices(), fine.len())?;
        let (even, odd) = fine.split_at(self.coarse_vertices);
        let acc = self.accumulate_odds(odd);
        let mut coarse: Vec<Vector3<f64>> = (0..self.coarse_vertices)
            .map(|i| (even[i] - acc[i] * self.gamma[i]) / self.alpha[i])
            .collect();
        let details: Vec<Vector3<f64>> = (0..self.edges.len())
            .map(|k| odd[k] - self.predict(k, &coarse))
            .collect();
        if let Some(kd) = &self.kdisk {
            kd.apply(&mut coarse, &details, 1.0);
        }
        Ok((coarse, details))
    }

    /// Synthesis on coordinate vectors: (coarse, details) → fine (length `V + E`).
    pub(super) fn synthesise_coords(
        &self,
        coarse: &[Vector3<f64>],
        details: &[Vector3<f64>],
    ) -> Result<Vec<Vector3<f64>>, WaveletError> {
        Self::check_len("coarse positions", self.coarse_vertices, coarse.len())?;
        Self::check_len("details", self.edges.len(), details.len())?;
        let lifted;
        let c: &[Vector3<f64>] = match &self.kdisk {
            Some(kd) => {
                let mut v = coarse.to_vec();
                kd.apply(&mut v, details, -1.0);
                lifted = v;
                &lifted
            }
            None => coarse,
        };
        let mut fine = Vec::with_capacity(self.fine_vertices());
        fine.resize(self.coarse_vertices, Vector3::zeros());
        for (k, d) in details.iter().enumerate() {
            fine.push(self.predict(k, c) + d);
        }
        let acc = self.accumulate_odds(&fine[self.coarse_vertices..]);
        for i in 0..self.coarse_vertices {
            fine[i] = c[i] * self.alpha[i] + acc[i] * self.gamma[i];
        }
        Ok(fine)
    }

    /// Analysis: fine positions (length `V_j + |E_j|`) → coarse positions and details.
    pub fn analyse(&self, fine: &[Point3<f64>]) -> Result<LevelWavelets, WaveletError> {
        let coords: Vec<Vector3<f64>> = fine.iter().map(|p| p.coords).collect();
        let (coarse, details) = self.analyse_coords(&coords)?;
        Ok(LevelWavelets {
            coarse: coarse.into_iter().map(Point3::from).collect(),
            details,
        })
    }

    /// Synthesis: coarse positions (length `V_j`) and details (length `|E_j|`) → fine
    /// positions. With all details zero (and no k-disk update) this is Loop subdivision.
    pub fn synthesise(
        &self,
        coarse: &[Point3<f64>],
        details: &[Vector3<f64>],
    ) -> Result<Vec<Point3<f64>>, WaveletError> {
        let coords: Vec<Vector3<f64>> = coarse.iter().map(|p| p.coords).collect();
        Ok(self
            .synthesise_coords(&coords, details)?
            .into_iter()
            .map(Point3::from)
            .collect())
    }
}

/// Result of one analysis step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LevelWavelets {
    /// Coarse positions, indexed by coarse vertex.
    pub coarse: Vec<Point3<f64>>,
    /// Details (mm), indexed by coarse edge k (the odd vertex `V_j + k`).
    pub details: Vec<Vector3<f64>>,
}

/// One analysis step with the plain lifting: see [`LevelTopology::analyse`].
pub fn analyse(
    split: &Split,
    creases: &Creases,
    fine: &[Point3<f64>],
) -> Result<LevelWavelets, WaveletError> {
    LevelTopology::new(split, creases)?.analyse(fine)
}

/// One synthesis step with the plain lifting: see [`LevelTopology::synthesise`].
pub fn synthesise(
    split: &Split,
    creases: &Creases,
    coarse: &[Point3<f64>],
    details: &[Vector3<f64>],
) -> Result<Vec<Point3<f64>>, WaveletError> {
    LevelTopology::new(split, creases)?.synthesise(coarse, details)
}

/// Size statistics of a set of details (Euclidean norms, mm).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DetailStats {
    /// Largest detail norm (0 when empty).
    pub max_norm: f64,
    /// Root mean square of the detail norms (0 when empty).
    pub rms_norm: f64,
    /// Number of details.
    pub count: usize,
}

/// Statistics of `details`.
pub fn detail_stats(details: &[Vector3<f64>]) -> DetailStats {
    let mut max_norm = 0.0f64;
    let mut sum_sq = 0.0;
    for d in details {
        let n2 = d.norm_squared();
        max_norm = max_norm.max(n2.sqrt());
        sum_sq += n2;
    }
    let count = details.len();
    let rms_norm = if count == 0 {
        0.0
    } else {
        (sum_sq / count as f64).sqrt()
    };
    DetailStats {
        max_norm,
        rms_norm,
        count,
    }
}
