//! The multi-level driver: analysis and synthesis over a whole hierarchy, truncation and the
//! exact L∞ deviation of a truncated level from the finest (DESIGN.md §3.4).

use nalgebra::{Point3, Vector3};

use super::WaveletError;
use super::level::{
    DetailStats, LevelTopology, WaveletOptions, coarse_triangles, detail_stats, refine_creases,
};
use crate::multires::{Creases, Split, split};

/// The connectivity of a hierarchy `M^0 ⊂ … ⊂ M^L` and its prepared lifting transforms.
#[derive(Clone, Debug)]
pub struct WaveletHierarchy {
    /// Vertex count of level 0.
    base_vertices: usize,
    /// Triangles of each level 0..=L.
    triangles: Vec<Vec<[u32; 3]>>,
    /// Creases of each level 0..=L.
    creases: Vec<Creases>,
    /// Transform from level j to j+1, j in 0..L.
    levels: Vec<LevelTopology>,
}

/// A hierarchy's wavelet representation: base positions and the details of every level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MultiresWavelets {
    /// Positions of the base mesh `M^0`.
    pub base: Vec<Point3<f64>>,
    /// `details[j]`: details of the step from level j to j+1, indexed by the edges of level j.
    pub details: Vec<Vec<Vector3<f64>>>,
}

impl MultiresWavelets {
    /// Detail statistics of each level, coarsest first.
    pub fn detail_stats(&self) -> Vec<DetailStats> {
        self.details.iter().map(|d| detail_stats(d)).collect()
    }

    /// A copy with every detail shorter than `threshold` (mm) set to zero, and how many
    /// details were kept: lossy compression of the hierarchy.
    pub fn thresholded(&self, threshold: f64) -> (Self, usize) {
        let mut kept = 0;
        let details = self
            .details
            .iter()
            .map(|level| {
                level
                    .iter()
                    .map(|d| {
                        if d.norm() >= threshold {
                            kept += 1;
                            *d
                        } else {
                            Vector3::zeros()
                        }
                    })
                    .collect()
            })
            .collect();
        (
            MultiresWavelets {
                base: self.base.clone(),
                details,
            },
            kept,
        )
    }

    /// A copy with every detail multiplied by `factor` (base unchanged).
    pub fn scaled_details(&self, factor: f64) -> Self {
        MultiresWavelets {
            base: self.base.clone(),
            details: self
                .details
                .iter()
                .map(|d| d.iter().map(|x| x * factor).collect())
                .collect(),
        }
    }
}

/// Deviation of a truncated reconstruction from the finest level, per finest vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Deviation {
    /// `truncated − finest` at each finest vertex (mm). Linear in the zeroed details.
    pub per_vertex: Vec<Vector3<f64>>,
    /// `max |per_vertex|`: the L∞ deviation (exact for the piecewise-linear surfaces on the
    /// common finest connectivity).
    pub linf: f64,
    /// A vertex where `linf` is reached (`None` when there are no vertices).
    pub argmax: Option<usize>,
}

impl WaveletHierarchy {
    /// Builds `levels` 1-to-4 splits of the base mesh (plain lifting).
    pub fn new(
        base_triangles: &[[u32; 3]],
        base_vertices: usize,
        base_creases: &Creases,
        levels: usize,
    ) -> Result<Self, WaveletError> {
        Self::new_opt(
            base_triangles,
            base_vertices,
            base_creases,
            levels,
            &WaveletOptions::default(),
        )
    }

    /// Like [`WaveletHierarchy::new`], with options.
    pub fn new_opt(
        base_triangles: &[[u32; 3]],
        base_vertices: usize,
        base_creases: &Creases,
        levels: usize,
        options: &WaveletOptions,
    ) -> Result<Self, WaveletError> {
        let mut splits = Vec::with_capacity(levels);
        let mut tris = base_triangles.to_vec();
        let mut nv = base_vertices;
        for _ in 0..levels {
            let s = split(&tris, nv);
            nv = s.coarse_vertices + s.edges.len();
            tris = s.triangles.clone();
            splits.push(s);
        }
        if levels == 0 {
            // Still validate the base connectivity through a split.
            coarse_triangles(&split(base_triangles, base_vertices))?;
        }
        let mut h = Self::from_splits(&splits, base_creases, options)?;
        if levels == 0 {
            h.triangles = vec![base_triangles.to_vec()];
            h.base_vertices = base_vertices;
        }
        Ok(h)
    }

    /// Builds the hierarchy from an existing stack of splits (split j+1 must split the fine
    /// level of split j). `base_creases` are the creases of level 0. With no splits the
    /// hierarchy has no levels and no triangles.
    pub fn from_splits(
        splits: &[Split],
        base_creases: &Creases,
        options: &WaveletOptions,
    ) -> Result<Self, WaveletError> {
        let mut triangles = Vec::with_capacity(splits.len() + 1);
        let mut creases = vec![base_creases.clone()];
        let mut levels = Vec::with_capacity(splits.len());
        for (j, s) in splits.iter().enumerate() {
            let coarse: Vec<[u32; 3]> = coarse_triangles(s)?
                .into_iter()
                .map(|t| t.vertices)
                .collect();
            if j == 0 {
                triangles.push(coarse);
            } else {
                let prev = &splits[j - 1];
                let nv = prev.coarse_vertices + prev.edges.len();
                if s.coarse_vertices != nv || coarse != prev.triangles {
                    return Err(WaveletError::InvalidSplit {
                        reason: format!(
                            "split {j} does not refine the fine level of split {}",
                            j - 1
                        ),
                    });
                }
            }
            triangles.push(s.triangles.clone());
            let level = LevelTopology::new_opt(s, &creases[j], options)?;
            creases.push(refine_creases(s, &creases[j])?);
            levels.push(level);
        }
        Ok(WaveletHierarchy {
            base_vertices: splits.first().map_or(0, |s| s.coarse_vertices),
            triangles,
            creases,
            levels,
        })
    }

    /// Number of splits L (levels are 0..=L).
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// The transform from level `j` to `j + 1`.
    pub fn level(&self, j: usize) -> Option<&LevelTopology> {
        self.levels.get(j)
    }

    /// Triangles of level `j` (0..=L).
    pub fn triangles(&self, j: usize) -> Option<&[[u32; 3]]> {
        self.triangles.get(j).map(Vec::as_slice)
    }

    /// Creases of level `j` (0..=L).
    pub fn creases(&self, j: usize) -> Option<&Creases> {
        self.creases.get(j)
    }

    /// Triangles of the finest level.
    pub fn finest_triangles(&self) -> &[[u32; 3]] {
        self.triangles.last().map(Vec::as_slice).unwrap_or(&[])
    }

    /// Vertex count of level `j` (0..=L).
    pub fn vertex_count(&self, j: usize) -> Option<usize> {
        match j {
            0 => Some(self.base_vertices),
            _ => self.levels.get(j - 1).map(LevelTopology::fine_vertices),
        }
    }

    /// Vertex count of the finest level.
    pub fn finest_vertices(&self) -> usize {
        self.levels
            .last()
            .map_or(self.base_vertices, LevelTopology::fine_vertices)
    }

    fn check_level(&self, j: usize) -> Result<(), WaveletError> {
        if j > self.levels.len() {
            return Err(WaveletError::LevelOutOfRange {
                level: j,
                levels: self.levels.len(),
            });
        }
        Ok(())
    }

    fn check_shape(&self, w: &MultiresWavelets) -> Result<(), WaveletError> {
        if w.details.len() != self.levels.len() {
            return Err(WaveletError::LengthMismatch {
                what: "detail levels",
                expected: self.levels.len(),
                found: w.details.len(),
            });
        }
        Ok(())
    }

    /// Full analysis: finest positions → base positions and details of every level.
    pub fn analyse_all(&self, finest: &[Point3<f64>]) -> Result<MultiresWavelets, WaveletError> {
        let mut cur: Vec<Vector3<f64>> = finest.iter().map(|p| p.coords).collect();
        let mut details = vec![Vec::new(); self.levels.len()];
        for (j, level) in self.levels.iter().enumerate().rev() {
            let (c, d) = level.analyse_coords(&cur)?;
            details[j] = d;
            cur = c;
        }
        Ok(MultiresWavelets {
            base: cur.into_iter().map(Point3::from).collect(),
            details,
        })
    }

    /// Synthesis from level `from` with coarse coordinates `c`, using the details of levels
    /// `from..` for which `keep(level)` holds (zero otherwise).
    fn synthesise_from(
        &self,
        from: usize,
        mut c: Vec<Vector3<f64>>,
        w: &MultiresWavelets,
        keep: impl Fn(usize) -> bool,
    ) -> Result<Vec<Vector3<f64>>, WaveletError> {
        for j in from..self.levels.len() {
            let level = &self.levels[j];
            c = if keep(j) {
                level.synthesise_coords(&c, &w.details[j])?
            } else {
                let zeros = vec![Vector3::zeros(); level.edge_count()];
                level.synthesise_coords(&c, &zeros)?
            };
        }
        Ok(c)
    }

    /// Full synthesis: the finest positions.
    pub fn synthesise_all(&self, w: &MultiresWavelets) -> Result<Vec<Point3<f64>>, WaveletError> {
        self.synthesise_truncated(w, self.levels.len())
    }

    /// Positions of level `j` (0..=L) reconstructed from the base and details of levels < j.
    pub fn level_positions(
        &self,
        w: &MultiresWavelets,
        j: usize,
    ) -> Result<Vec<Point3<f64>>, WaveletError> {
        self.check_level(j)?;
        self.check_shape(w)?;
        let mut c: Vec<Vector3<f64>> = w.base.iter().map(|p| p.coords).collect();
        for (level, d) in self.levels[..j].iter().zip(&w.details) {
            c = level.synthesise_coords(&c, d)?;
        }
        Ok(c.into_iter().map(Point3::from).collect())
    }

    /// The finest-connectivity surface with the details of levels ≥ `j` zeroed, i.e. the
    /// level-`j` positions Loop-subdivided to the finest level. `j = L` gives the finest
    /// level, `j = 0` the Loop-subdivided base.
    pub fn synthesise_truncated(
        &self,
        w: &MultiresWavelets,
        j: usize,
    ) -> Result<Vec<Point3<f64>>, WaveletError> {
        self.check_level(j)?;
        self.check_shape(w)?;
        let base: Vec<Vector3<f64>> = w.base.iter().map(|p| p.coords).collect();
        Ok(self
            .synthesise_from(0, base, w, |l| l < j)?
            .into_iter()
            .map(Point3::from)
            .collect())
    }

    /// `synthesise_truncated(j) − finest` per finest vertex and its L∞ norm, computed by
    /// linearity as `−synthesis(0, details of levels ≥ j)`: it depends only on the zeroed
    /// details (scale them by s and the deviation scales by s).
    pub fn deviation_to_finest(
        &self,
        w: &MultiresWavelets,
        j: usize,
    ) -> Result<Deviation, WaveletError> {
        self.check_level(j)?;
        self.check_shape(w)?;
        // Level j's vertex count; with j == 0 synthesis checks it against the base length.
        let nj = match j {
            0 => w.base.len(),
            _ => self.levels[j - 1].fine_vertices(),
        };
        let high = self.synthesise_from(j, vec![Vector3::zeros(); nj], w, |_| true)?;
        let mut linf = 0.0f64;
        let mut argmax = None;
        let per_vertex: Vec<Vector3<f64>> = high
            .into_iter()
            .enumerate()
            .map(|(i, x)| {
                let n = x.norm();
                if argmax.is_none() || n > linf {
                    linf = n;
                    argmax = Some(i);
                }
                -x
            })
            .collect();
        Ok(Deviation {
            per_vertex,
            linf,
            argmax,
        })
    }
}
