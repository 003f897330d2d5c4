//! Terrain queries on a `parry3d` triangle mesh of the smoothed surface: distance to the surface, altitude over
//! it, ray casts.
//!
//! parry 0.31 works on glam vectors (`DVec3` in its f64 build, ECOSYSTEM.md); this module is the boundary:
//! everything outside it speaks `[f64; 3]` metres in the map frame. The mesh has a vertex at every cell centre
//! and two triangles per square of centres, split along the (i, j)–(i+1, j+1) diagonal, wound counter-clockwise
//! seen from above (normals up) — the same triangles [`TerrainSurface::height_at`] interpolates on.

use parry3d_f64::math::Vector;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use parry3d_f64::shape::TriMesh;

use super::surface::TerrainSurface;
use crate::error::{PlannerError, Result};

fn vec3(p: [f64; 3]) -> Vector {
    Vector::new(p[0], p[1], p[2])
}

/// The smoothed surface as a triangle mesh, for queries.
pub struct TerrainMesh {
    mesh: TriMesh,
    /// Highest vertex, metres: vertical rays start above it.
    top_m: f64,
    /// Lowest vertex, metres.
    bottom_m: f64,
}

impl std::fmt::Debug for TerrainMesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TerrainMesh")
            .field("triangles", &self.mesh.indices().len())
            .field("top_m", &self.top_m)
            .field("bottom_m", &self.bottom_m)
            .finish()
    }
}

impl TerrainMesh {
    /// Builds the mesh of a surface. Refuses one whose vertices do not fit parry's 32-bit indices.
    pub fn new(surface: &TerrainSurface) -> Result<Self> {
        let g = &surface.geometry;
        let n = g.len();
        if n > u32::MAX as usize {
            return Err(PlannerError::TerrainTooLarge {
                field: "mesh vertices",
                needed: n,
                limit: u32::MAX as usize,
            });
        }
        let vertices: Vec<Vector> = (0..n).map(|i| vec3(surface.landmark(i))).collect();
        let mut indices = Vec::with_capacity(2 * (g.width - 1) * (g.height - 1));
        for j in 0..g.height - 1 {
            for i in 0..g.width - 1 {
                let v = |a: usize, b: usize| ((j + b) * g.width + i + a) as u32;
                indices.push([v(0, 0), v(1, 0), v(1, 1)]);
                indices.push([v(0, 0), v(1, 1), v(0, 1)]);
            }
        }
        let (mut top_m, mut bottom_m) = (f64::NEG_INFINITY, f64::INFINITY);
        for h in &surface.heights {
            top_m = top_m.max(*h);
            bottom_m = bottom_m.min(*h);
        }
        let mesh = TriMesh::new(vertices, indices).map_err(|e| PlannerError::InvalidParam {
            name: "terrain mesh",
            reason: e.to_string(),
        })?;
        Ok(Self { mesh, top_m, bottom_m })
    }

    /// Number of triangles.
    pub fn triangles(&self) -> usize {
        self.mesh.indices().len()
    }

    /// Height of the surface under map-frame (x, y), metres, by a vertical ray cast from above; `None` off the
    /// mesh or for a non-finite input.
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let start = self.top_m + 1.0;
        let reach = start - self.bottom_m + 1.0;
        self.cast_ray([x, y, start], [0.0, 0.0, -1.0], reach).map(|t| start - t)
    }

    /// Height of `p` over the surface right under it (negative below it), metres; `None` off the mesh.
    pub fn altitude(&self, p: [f64; 3]) -> Option<f64> {
        self.height_at(p[0], p[1]).map(|h| p[2] - h)
    }

    /// Euclidean distance from `p` to the nearest point of the surface, metres.
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.mesh.distance_to_local_point(vec3(p), false)
    }

    /// Distance along the unit direction `dir` from `origin` to the first hit of the surface within
    /// `max_m`, metres.
    pub fn cast_ray(&self, origin: [f64; 3], dir: [f64; 3], max_m: f64) -> Option<f64> {
        let ray = Ray::new(vec3(origin), vec3(dir));
        self.mesh.cast_local_ray(&ray, max_m, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;
    use crate::map::GridGeometry;

    fn cap(r: f64) -> TerrainSurface {
        let geometry = GridGeometry::new(60, 60, 0.1, Point2::new(-3.0, -3.0)).expect("geometry");
        TerrainSurface::from_fn(geometry, |x, y| (r * r - x * x - y * y).sqrt()).expect("surface")
    }

    #[test]
    fn a_ray_from_above_hits_a_sphere_cap_at_its_height() {
        let r = 5.0;
        let s = cap(r);
        let m = TerrainMesh::new(&s).expect("mesh");
        assert_eq!(m.triangles(), 2 * 59 * 59);
        let mut worst_mesh = 0.0f64;
        let mut worst_sphere = 0.0f64;
        for k in 0..400 {
            // A deterministic scatter over the domain [-2.95, 2.95]².
            let x = -2.9 + 5.8 * ((k * 37 % 400) as f64 / 399.0);
            let y = -2.9 + 5.8 * ((k * 91 % 400) as f64 / 399.0);
            let hit = m.height_at(x, y).expect("hit");
            worst_mesh = worst_mesh.max((hit - s.height_at(x, y).expect("inside")).abs());
            worst_sphere = worst_sphere.max((hit - (r * r - x * x - y * y).sqrt()).abs());
        }
        eprintln!("ray cast on a sphere cap: vs the surface {worst_mesh:.2e} m, vs the sphere {worst_sphere:.2e} m");
        assert!(worst_mesh < 1e-9, "mesh vs surface {worst_mesh}");
        // Vertical sag of a triangle of edge g√2: z''·(g√2)²/8 with z'' up to R²/(R² − r²)^1.5 = 1.07 1/m at the
        // corners (r = 4.1 m): 2.7e-3 m; measured 2.68e-3 m.
        assert!(worst_sphere < 3e-3, "mesh vs sphere {worst_sphere}");
        assert_eq!(m.height_at(10.0, 0.0), None);
        assert_eq!(m.height_at(f64::NAN, 0.0), None);
    }

    #[test]
    fn altitude_and_distance_over_a_sphere_cap() {
        let r = 5.0;
        let m = TerrainMesh::new(&cap(r)).expect("mesh");
        let alt = m.altitude([0.0, 0.0, r + 2.0]).expect("over the mesh");
        assert!((alt - 2.0).abs() < 1e-3, "altitude {alt}");
        // Off the top at (1, 1): the nearest surface point lies along the sphere's radius.
        let p = [1.0, 1.0, (r * r - 2.0f64).sqrt() + 1.0];
        let radial = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - r;
        assert!(
            (m.distance(p) - radial).abs() < 2e-3,
            "distance {} vs {radial}",
            m.distance(p)
        );
        let down = m.cast_ray([0.0, 0.0, 10.0], [0.0, 0.0, -1.0], 100.0).expect("hit");
        assert!((down - (10.0 - r)).abs() < 1e-3);
        assert_eq!(m.cast_ray([0.0, 0.0, 10.0], [0.0, 0.0, 1.0], 100.0), None);
    }
}
