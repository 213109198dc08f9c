//! [`DeformRig`]: the once-per-mesh part of the deformation. Takes a rest mesh, a
//! [`LaplacianKind`] and [`DeformOptions`]; keeps the rest geometry, per-triangle centroids
//! and share-weighted edge vectors, the rest centroid (default pivot), the assembled Laplacian
//! and its own [`PenaltyFactor`], plus the per-frame scratch that [`step`](super::step) reuses.

use super::falloff::HandleFalloff;
use super::weights::{assemble_laplacian, edge_shares};
use super::{DeformError, DeformOptions, Handle};
use crate::mesh::Mesh;
use crate::solve::{LaplacianKind, PenaltyFactor, SymmetricCsc};
use glam::DVec2;

/// Per-handle values derived once per frame.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HandleFrame {
    pub vertex: usize,
    pub theta: f64,
    /// `1 / (2σ²)`.
    pub rate: f64,
    /// Squared distance beyond which the falloff is below the far-field cutoff.
    pub far_d2: f64,
    pub core_d2: f64,
    pub depth: f32,
}

/// Once-per-mesh deformation state plus reusable per-frame scratch. See the `deform` module.
pub struct DeformRig {
    pub(crate) options: DeformOptions,
    pub(crate) rest: Vec<DVec2>,
    pub(crate) triangles: Vec<[u32; 3]>,
    pub(crate) centroids: Vec<DVec2>,
    /// `edge_terms[t][k] = w^t_k (p_{corner k} − p_{corner k+1})`.
    pub(crate) edge_terms: Vec<[DVec2; 3]>,
    pub(crate) rest_centroid: DVec2,
    pub(crate) laplacian: SymmetricCsc,
    pub(crate) factor: PenaltyFactor,
    // Per-frame scratch.
    pub(crate) frames: Vec<HandleFrame>,
    /// Per handle slot: its falloff weights, kept while its grab point and rate hold.
    pub(crate) falloff: Vec<HandleFalloff>,
    pub(crate) theta: Vec<f64>,
    pub(crate) wanted: Vec<bool>,
    pub(crate) pinned: Vec<bool>,
    /// Target displacement `c_v − p_v` of constrained vertices.
    pub(crate) target: Vec<DVec2>,
    /// Column-major n×2 right-hand side / solution (x then y).
    pub(crate) rhs: Vec<f64>,
}

impl DeformRig {
    /// Builds the rig with default [`DeformOptions`].
    pub fn new(mesh: &Mesh, kind: LaplacianKind) -> Result<Self, DeformError> {
        Self::with_options(mesh, kind, DeformOptions::default())
    }

    /// Builds the rig: validates the mesh, computes shares, Laplacian and factor.
    pub fn with_options(
        mesh: &Mesh,
        kind: LaplacianKind,
        options: DeformOptions,
    ) -> Result<Self, DeformError> {
        validate_mesh(mesh)?;
        validate_options(&options)?;
        let n = mesh.vertex_count();
        let shares = edge_shares(mesh, kind);
        let laplacian = assemble_laplacian(n, &mesh.triangles, &shares);
        let factor = PenaltyFactor::new(&laplacian, &options.penalty)?;
        let p = &mesh.positions;
        let corners = |t: &[u32; 3]| t.map(|v| p[v as usize]);
        let centroids = mesh
            .triangles
            .iter()
            .map(|t| corners(t).iter().sum::<DVec2>() / 3.0)
            .collect();
        let edge_terms = mesh
            .triangles
            .iter()
            .zip(&shares)
            .map(|(t, w)| {
                let c = corners(t);
                [0, 1, 2].map(|k| w[k] * (c[k] - c[(k + 1) % 3]))
            })
            .collect();
        Ok(Self {
            options,
            rest: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            centroids,
            edge_terms,
            rest_centroid: area_weighted_centroid(mesh),
            laplacian,
            factor,
            frames: Vec::new(),
            falloff: Vec::new(),
            theta: vec![0.0; mesh.triangles.len()],
            wanted: vec![false; n],
            pinned: vec![false; n],
            target: vec![DVec2::ZERO; n],
            rhs: vec![0.0; 2 * n],
        })
    }

    /// Vertices of the rest mesh.
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// The rest positions the deformation starts from.
    pub fn rest_positions(&self) -> &[DVec2] {
        &self.rest
    }

    /// Area-weighted rest centroid: the default pivot o.
    pub fn rest_centroid(&self) -> DVec2 {
        self.rest_centroid
    }

    /// The options the rig was built with.
    pub fn options(&self) -> &DeformOptions {
        &self.options
    }

    internal_fn! {
        /// The Laplacian the rig factors (assembled from the per-triangle shares).
        fn laplacian(&self) -> &SymmetricCsc {
            &self.laplacian
        }
    }

    internal_fn! {
        /// The rig's own penalty factor (its constrained set is the last frame's).
        fn factor(&self) -> &PenaltyFactor {
            &self.factor
        }
    }

    /// Vertices constrained in the last solved frame (far field, pins and handles).
    pub fn constrained(&self) -> &[bool] {
        self.factor.constrained()
    }

    /// Index of the rest vertex nearest `point` (lowest index on ties).
    pub fn nearest_vertex(&self, point: DVec2) -> usize {
        let mut best = (f64::INFINITY, 0usize);
        for (v, p) in self.rest.iter().enumerate() {
            let d2 = p.distance_squared(point);
            if d2 < best.0 {
                best = (d2, v);
            }
        }
        best.1
    }

    /// Brings `self.falloff[h]` up to date for each of `handles` (slots grow only).
    pub(crate) fn update_falloff(&mut self, handles: &[Handle]) {
        if self.falloff.len() < handles.len() {
            self.falloff
                .resize_with(handles.len(), HandleFalloff::default);
        }
        for ((h, frame), slot) in handles.iter().zip(&self.frames).zip(&mut self.falloff) {
            slot.refresh(h.from, frame.rate, &self.centroids, &self.rest);
        }
    }
}

fn validate_mesh(mesh: &Mesh) -> Result<(), DeformError> {
    let n = mesh.vertex_count();
    if n == 0 || mesh.triangles.is_empty() {
        return Err(DeformError::EmptyMesh);
    }
    if let Some(v) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(DeformError::InvalidMesh(format!(
            "vertex {v} has a non-finite position"
        )));
    }
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri.iter().any(|&v| v as usize >= n) {
            return Err(DeformError::InvalidMesh(format!(
                "triangle {t} names a vertex ≥ {n}"
            )));
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
            return Err(DeformError::InvalidMesh(format!(
                "triangle {t} repeats a vertex"
            )));
        }
    }
    Ok(())
}

fn validate_options(options: &DeformOptions) -> Result<(), DeformError> {
    if !(options.far_cutoff > 0.0 && options.far_cutoff < 1.0) {
        return Err(DeformError::InvalidOptions(format!(
            "far_cutoff {} must lie in (0, 1)",
            options.far_cutoff
        )));
    }
    if !(options.core_fraction >= 0.0 && options.core_fraction.is_finite()) {
        return Err(DeformError::InvalidOptions(format!(
            "core_fraction {} must be finite and ≥ 0",
            options.core_fraction
        )));
    }
    Ok(())
}

/// Area-weighted centroid of the triangles (vertex mean if the total area is zero).
fn area_weighted_centroid(mesh: &Mesh) -> DVec2 {
    let (mut weighted, mut total) = (DVec2::ZERO, 0.0);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let area = 0.5 * (b - a).perp_dot(c - a).abs();
        weighted += area * (a + b + c) / 3.0;
        total += area;
    }
    if total > 0.0 {
        weighted / total
    } else {
        mesh.positions.iter().sum::<DVec2>() / mesh.vertex_count() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::super::falloff::gaussian;
    use super::*;
    use crate::mesh::{mesh_mask, synth, MeshOptions};
    use crate::solve::LaplacianKind;

    /// After every update, each slot in use holds exactly the fresh weights of its handle.
    #[test]
    fn kept_weights_are_the_fresh_ones_after_any_sequence_of_handles() {
        let mask = synth::disc(40, 40, 17.0);
        let mesh = mesh_mask(&mask, &MeshOptions::default()).unwrap().mesh;
        let mut rig = DeformRig::new(&mesh, LaplacianKind::Combinatorial).unwrap();
        let a = DVec2::new(15.0, 18.0);
        let b = DVec2::new(25.0, 21.0);
        let drag = |from: DVec2, to: DVec2, radius: f64| Handle::drag(from, to, radius);
        // p1 moves (weights kept), p0 moves, the radius changes, a handle is added, the
        // handles swap slots, one is dropped and comes back.
        let frames = [
            vec![drag(a, b, 10.0)],
            vec![drag(a, b + DVec2::X, 10.0)],
            vec![drag(a + DVec2::Y, b, 10.0)],
            vec![drag(a + DVec2::Y, b, 12.0)],
            vec![drag(a + DVec2::Y, b, 12.0), drag(b, a, 6.0)],
            vec![drag(b, a, 6.0), drag(a + DVec2::Y, b, 12.0)],
            vec![drag(b, a, 6.0)],
            vec![drag(b, a, 6.0), drag(a + DVec2::Y, b, 12.0)],
        ];
        for (k, handles) in frames.iter().enumerate() {
            rig.prepare_handles(handles).unwrap();
            rig.update_falloff(handles);
            for (slot, (h, frame)) in rig.falloff.iter().zip(handles.iter().zip(&rig.frames)) {
                let fresh = |points: &[DVec2]| -> Vec<u64> {
                    points
                        .iter()
                        .map(|&x| gaussian(frame.rate, x, h.from).to_bits())
                        .collect()
                };
                let bits = |w: &[f64]| -> Vec<u64> { w.iter().map(|v| v.to_bits()).collect() };
                assert_eq!(bits(&slot.triangles), fresh(&rig.centroids), "frame {k}");
                assert_eq!(bits(&slot.vertices), fresh(&rig.rest), "frame {k}");
            }
        }
    }
}
