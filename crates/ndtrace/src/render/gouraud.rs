//! Gouraud shading (`render.shading = "gouraud"`; notes Part II(B), "4D Shading": "dot product
//! of light with 4D versions of usual vectors give Gouraud and Phong models"): each light's
//! diffuse and specular factors evaluated at the vertices of the hit simplex and interpolated
//! with the hit's barycentric coordinates, instead of at the hit point (Phong). The shadow ray
//! still leaves the hit point.

use crate::linalg::{dot, scale, Vector};
use crate::ray::{Hit, Ray};
use crate::scene::Scene;

/// The interpolated factors Σ_k b_k·f_k of a light at a hit on simplex `local` of object
/// `obj`, b_k the hit's barycentric coordinates and f_k = `at_vertex(x_k, n̂_k)` the light's
/// (diffuse, specular) factors at vertex k (`shade::vertex_factors`), n̂_k its unit normal (the
/// object's vertex normal, or the simplex's flat one; turned like the hit's for two-sided
/// lighting when `flip`). A vertex with no factors adds nothing.
#[inline(never)]
pub(crate) fn factors<const N: usize>(
    scene: &Scene<N>,
    (obj, local): (usize, usize),
    hit: &Hit<N>,
    flip: bool,
    at_vertex: impl Fn(&Vector<N>, &Vector<N>) -> Option<(f64, f64)>,
) -> (f64, f64) {
    let o = &scene.objects[obj];
    let idx = &o.mesh.simplices[local];
    let (mut diffuse, mut spec) = (0.0, 0.0);
    for k in 0..N {
        let x = o.mesh.vertices[idx[k] as usize];
        let n: Vector<N> = match &o.vertex_normals {
            Some(vn) => vn[idx[k] as usize],
            None => hit.normal,
        };
        let n = if flip { scale(&n, -1.0) } else { n };
        if let Some((d, s)) = at_vertex(&x, &n) {
            diffuse += hit.bary[k] * d;
            spec += hit.bary[k] * s;
        }
    }
    (diffuse, spec)
}

/// Whether the hit's lighting turns normals toward the viewer (two-sided lighting of a simplex
/// seen from behind), as [`super::shade::shading_normal`] decides it.
#[inline(always)]
pub(crate) fn flipped<const N: usize>(scene: &Scene<N>, hit: &Hit<N>, ray: &Ray<N>) -> bool {
    scene.render.two_sided && dot(&hit.normal, &ray.dir) > 0.0
}
