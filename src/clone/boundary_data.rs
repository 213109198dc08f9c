//! The membrane's Dirichlet data along the boundary: takes a patch mesh's boundary loops and
//! a colour sampler (the source at rest, the canvas where the patch is placed) and gives one
//! RGB value per boundary vertex.
//!
//! The membrane is linear along every boundary edge, so between two vertices it can only
//! follow the data's trend. Sampling the data at the vertex alone (the paper's
//! `f_T(p_v) − f_S(v)`, [`BoundaryData::Vertex`]) lets the texture at that one point stand
//! for the whole stretch, and the error it aliases into the boundary values reaches far
//! inside. The default, [`BoundaryData::HatAverage`], weights the data along the vertex's
//! two boundary edges by the vertex's hat function (1 at the vertex, 0 at the neighbours),
//! sampled at most √2 px apart — the lumped L2 projection of the data onto the boundary's
//! linear functions. It equals the vertex sample where edges are at most √2 px long (a mesh
//! through every outside pixel centre keeps its exact data), and for constant data; on the
//! paper's spiral it brings the membrane 1.3 / 2.1 dB (combinatorial / cotangent) closer to
//! the pixel-grid solution at the default density (docs/quality.md).
//!
//! The samples are planned once per mesh, in rest pixels, so a patch placed at scale s is
//! sampled every s·√2 target pixels or closer: the per-call work stays fixed and allocation
//! free, and a patch scaled up averages the target more coarsely.

use glam::DVec2;

use crate::mesh::Mesh;

/// Which Dirichlet value each boundary vertex gets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BoundaryData {
    /// `target − source` sampled (bilinearly) at the vertex: the paper's constraint.
    Vertex,
    /// `target − source` averaged along the vertex's boundary edges, weighted by its hat
    /// function and sampled at most √2 px apart (see the module documentation).
    #[default]
    HatAverage,
}

impl BoundaryData {
    /// The name `--boundary-data` and [`FromStr`](std::str::FromStr) use.
    pub fn name(self) -> &'static str {
        match self {
            Self::Vertex => "vertex",
            Self::HatAverage => "hat-average",
        }
    }
}

impl std::str::FromStr for BoundaryData {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text {
            "vertex" => Ok(Self::Vertex),
            "hat-average" => Ok(Self::HatAverage),
            other => Err(format!(
                "unknown boundary data {other:?} (expected vertex or hat-average)"
            )),
        }
    }
}

/// The largest spacing, in rest pixels, between two samples of a hat average.
pub const HAT_SAMPLE_SPACING: f64 = std::f64::consts::SQRT_2;

/// The sampling plan of one mesh's boundary data, built once per mesh.
#[derive(Clone, Debug)]
pub struct BoundarySampler {
    kind: BoundaryData,
    /// The boundary vertices, in the order of the values given out ("slots").
    boundary: Vec<u32>,
    /// Boundary edges that need samples between their ends (hat average only).
    edges: Vec<SampledEdge>,
    /// Per slot: the hat weight of the vertex's own sample, and 1 / the hat's total weight.
    own_weight: Vec<f32>,
    inverse_mass: Vec<f32>,
}

/// One boundary edge split into `intervals` equal parts, each of length `step`.
#[derive(Clone, Copy, Debug)]
struct SampledEdge {
    from: u32,
    to: u32,
    from_slot: u32,
    to_slot: u32,
    intervals: u32,
    step: f32,
}

impl BoundarySampler {
    /// The plan for `mesh`'s boundary vertices (in index order) under `kind`.
    pub fn new(mesh: &Mesh, kind: BoundaryData) -> Self {
        let boundary: Vec<u32> = mesh.boundary_vertices().collect();
        let mut sampler = Self {
            kind,
            boundary,
            edges: Vec::new(),
            own_weight: Vec::new(),
            inverse_mass: Vec::new(),
        };
        if kind == BoundaryData::HatAverage {
            sampler.plan_hat_average(mesh);
        }
        sampler
    }

    fn plan_hat_average(&mut self, mesh: &Mesh) {
        let mut slot_of = vec![u32::MAX; mesh.vertex_count()];
        for (slot, &v) in self.boundary.iter().enumerate() {
            slot_of[v as usize] = slot as u32;
        }
        let mut own_weight = vec![0.0f64; self.boundary.len()];
        let mut mass = vec![0.0f64; self.boundary.len()];
        for boundary_loop in &mesh.loops {
            let vertices = &boundary_loop.vertices;
            for (i, &from) in vertices.iter().enumerate() {
                let to = vertices[(i + 1) % vertices.len()];
                let length = (mesh.positions[to as usize] - mesh.positions[from as usize]).length();
                // An edge of exactly the spacing (a pixel diagonal) gets no sample between its
                // ends, even when its length rounds an ulp above.
                let intervals = (length / HAT_SAMPLE_SPACING - 1e-9).ceil().max(1.0);
                let step = length / intervals;
                let [from_slot, to_slot] = [from, to].map(|v| slot_of[v as usize]);
                // Trapezoid rule: each end sample carries half a step of its own hat, and
                // the hat integrates to half the edge's length on each edge.
                for slot in [from_slot, to_slot] {
                    own_weight[slot as usize] += 0.5 * step;
                    mass[slot as usize] += 0.5 * length;
                }
                if intervals > 1.0 {
                    self.edges.push(SampledEdge {
                        from,
                        to,
                        from_slot,
                        to_slot,
                        intervals: intervals as u32,
                        step: step as f32,
                    });
                }
            }
        }
        // A boundary vertex lies on at least one loop edge, so its mass is positive.
        self.inverse_mass = mass.iter().map(|&m| (1.0 / m) as f32).collect();
        self.own_weight = own_weight.iter().map(|&w| w as f32).collect();
    }

    pub fn kind(&self) -> BoundaryData {
        self.kind
    }

    /// The boundary vertices, in the order [`sample`](Self::sample) writes their values.
    pub fn boundary_vertices(&self) -> &[u32] {
        &self.boundary
    }

    /// Writes each boundary vertex's value into `values` (one per slot): `sample` is called
    /// at `positions` of the vertices and, for a hat average, at points along the edges
    /// between them (linear in `positions`, so a placed or deformed mesh is sampled along its
    /// own edges). Allocates nothing.
    pub fn sample(
        &self,
        positions: &[DVec2],
        mut sample: impl FnMut(DVec2) -> [f32; 3],
        values: &mut [[f32; 3]],
    ) {
        for (value, &v) in values.iter_mut().zip(&self.boundary) {
            *value = sample(positions[v as usize]);
        }
        if self.kind == BoundaryData::Vertex {
            return;
        }
        for (value, &own) in values.iter_mut().zip(&self.own_weight) {
            *value = value.map(|c| c * own);
        }
        for edge in &self.edges {
            let (a, b) = (positions[edge.from as usize], positions[edge.to as usize]);
            let inverse_intervals = 1.0 / f64::from(edge.intervals);
            for j in 1..edge.intervals {
                let t = f64::from(j) * inverse_intervals;
                let colour = sample(a.lerp(b, t));
                let to_weight = t as f32 * edge.step;
                let from_weight = edge.step - to_weight;
                add_scaled(&mut values[edge.from_slot as usize], colour, from_weight);
                add_scaled(&mut values[edge.to_slot as usize], colour, to_weight);
            }
        }
        for (value, &inverse) in values.iter_mut().zip(&self.inverse_mass) {
            *value = value.map(|c| c * inverse);
        }
    }
}

fn add_scaled(sum: &mut [f32; 3], colour: [f32; 3], weight: f32) {
    for (s, c) in sum.iter_mut().zip(colour) {
        *s += weight * c;
    }
}
