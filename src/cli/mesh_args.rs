//! Mesh-quality flags shared by `mesh`, `clone`, `bench clone` and `bench paper`: takes the parsed
//! flags and gives them applied to [`MeshOptions`] (unset flags keep the library defaults).

use lapclone::mesh::{BoundaryPlacement, MeshOptions};

use super::UsageError;

#[derive(clap::Args, Debug, Clone, Default)]
pub struct MeshQualityArgs {
    /// Start from the seam-quality preset (`MeshOptions::seam_quality`: boundary on every
    /// Dirichlet pixel centre, density 1, 29°, 5 relaxation sweeps) instead of the defaults;
    /// the other flags still override it.
    #[arg(long)]
    pub seam_quality: bool,
    /// Where a mask mesh's boundary runs: `outside-centres` (the default: through the
    /// pixel-grid clone's Dirichlet pixel centres, thinned to the density where straight) or
    /// `cracks` (simplified, then moved half a pixel out).
    #[arg(long)]
    pub boundary: Option<BoundaryPlacement>,
    /// Minimum triangle angle of the refinement, degrees (0–35).
    #[arg(long, value_parser = super::finite_f64, allow_hyphen_values = true)]
    pub min_angle: Option<f64>,
    /// Largest triangle area refinement leaves, px².
    #[arg(long, value_parser = super::finite_f64, allow_hyphen_values = true)]
    pub max_area: Option<f64>,
    /// Sweeps moving interior vertices towards their neighbours' mean (combinatorial
    /// Laplacian accuracy; same vertex count).
    #[arg(long, allow_hyphen_values = true)]
    pub relax: Option<usize>,
}

impl MeshQualityArgs {
    /// The library defaults with these flags and `--density` applied, validated (an invalid
    /// combination is a usage error).
    pub fn options(&self, density: Option<f64>) -> Result<MeshOptions, UsageError> {
        let mut options = MeshOptions::default();
        self.apply(&mut options);
        if let Some(density) = density {
            options.density = density;
        }
        options.validate().map_err(|e| UsageError(e.to_string()))?;
        Ok(options)
    }

    /// Overrides the fields whose flags were given; `--seam-quality` replaces all options, so
    /// callers apply their own flags (`--density`) after this.
    fn apply(&self, options: &mut MeshOptions) {
        if self.seam_quality {
            *options = MeshOptions::seam_quality();
        }
        if let Some(boundary) = self.boundary {
            options.boundary = boundary;
        }
        if let Some(angle) = self.min_angle {
            options.min_angle_deg = angle;
        }
        if self.max_area.is_some() {
            options.max_area = self.max_area;
        }
        if let Some(sweeps) = self.relax {
            options.relax_sweeps = sweeps;
        }
    }
}
