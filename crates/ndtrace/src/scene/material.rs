//! Materials and textures: a `material` table checked and resolved to RGB coefficients
//! (course notes, Part II(B) "4D Shading": the Lambert and Blinn–Phong terms), with its
//! texture keys (colormap, isolines, cubic lattice: Part II(B)'s cues for 3D fields).

use super::desc::MaterialDesc;
use super::errors::PathError;
use super::fields::{coefficient, rgb, R};
use crate::linalg::Rgb;

/// Surface appearance with every coefficient resolved to RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Base colour.
    pub color: Rgb,
    /// Ambient coefficient.
    pub ambient: Rgb,
    /// Diffuse coefficient.
    pub diffuse: Rgb,
    /// Specular coefficient.
    pub specular: Rgb,
    /// Blinn–Phong exponent.
    pub shininess: f64,
    /// Interpolated vertex normals (surfaces: tangent planes).
    pub smooth: bool,
    /// Fraction of light stopped (surface objects; 1 for every other object).
    pub opacity: f64,
    /// Colour varying over the object: colormap, isolines, lattice.
    pub texture: Option<crate::texture::TextureSpec>,
}

/// The material a `material` table describes, its coefficients resolved to RGB and checked
/// (`path` locates errors).
pub(super) fn material(m: &MaterialDesc, path: &str) -> R<Material> {
    if !(m.opacity > 0.0 && m.opacity <= 1.0) {
        return Err(PathError::new(
            format!("{path}.opacity"),
            format!("must be in (0, 1], got {}", m.opacity),
        ));
    }
    if !(m.shininess >= 0.0 && m.shininess.is_finite()) {
        return Err(PathError::new(
            format!("{path}.shininess"),
            format!("must be a finite number ≥ 0, got {}", m.shininess),
        ));
    }
    Ok(Material {
        color: rgb(&m.color, &format!("{path}.color"))?,
        ambient: coefficient(&m.ambient, &format!("{path}.ambient"))?,
        diffuse: coefficient(&m.diffuse, &format!("{path}.diffuse"))?,
        specular: coefficient(&m.specular, &format!("{path}.specular"))?,
        shininess: m.shininess,
        smooth: m.smooth,
        opacity: m.opacity,
        texture: texture_spec(m, path)?,
    })
}

/// The texture keys of a material (`colormap`, `range`, `isolines`, `lattice`).
fn texture_spec(m: &MaterialDesc, path: &str) -> R<Option<crate::texture::TextureSpec>> {
    use crate::texture::{colormap, Isolines, Lattice, TextureSpec};
    let colormap = match &m.colormap {
        None => {
            if m.range.is_some() {
                return Err(PathError::new(
                    format!("{path}.range"),
                    "\"range\" sets the values at a colormap's ends: give material.colormap",
                ));
            }
            None
        }
        Some(name) => {
            let map = colormap::get(name).ok_or_else(|| {
                PathError::new(
                    format!("{path}.colormap"),
                    format!(
                        "unknown colormap \"{name}\" (known: {}; \"_r\" reverses one)",
                        colormap::names().join(", ")
                    ),
                )
            })?;
            let range = match &m.range {
                None => None,
                Some(r) => match r[..] {
                    [lo, hi] if lo.is_finite() && hi.is_finite() && hi != lo => Some([lo, hi]),
                    _ => {
                        return Err(PathError::new(
                            format!("{path}.range"),
                            format!(
                                "expected [low, high], two different finite numbers, got {r:?}"
                            ),
                        ))
                    }
                },
            };
            Some((map, range))
        }
    };
    let positive = |x: f64, key: &str| -> R<f64> {
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(PathError::new(
                format!("{path}.{key}"),
                format!("must be a finite number > 0, got {x}"),
            ))
        }
    };
    let isolines = match &m.isolines {
        None => None,
        Some(i) => {
            if let Some(k) = i.values.iter().position(|v| !v.is_finite()) {
                return Err(PathError::new(
                    format!("{path}.isolines.values[{k}]"),
                    format!("must be finite, got {}", i.values[k]),
                ));
            }
            Some(Isolines {
                values: i.values.clone(),
                width: positive(i.width.unwrap_or(0.03), "isolines.width")?,
                color: match &i.color {
                    Some(c) => rgb(c, &format!("{path}.isolines.color"))?,
                    None => [0.02, 0.02, 0.02],
                },
            })
        }
    };
    let lattice = match &m.lattice {
        None => None,
        Some(l) => {
            let spacing = positive(l.spacing, "lattice.spacing")?;
            let width = positive(l.width.unwrap_or(spacing / 12.0), "lattice.width")?;
            if width >= spacing {
                return Err(PathError::new(
                    format!("{path}.lattice.width"),
                    format!("must be less than the spacing {spacing}, got {width}"),
                ));
            }
            Some(Lattice {
                spacing,
                width,
                color: match &l.color {
                    Some(c) => rgb(c, &format!("{path}.lattice.color"))?,
                    None => [1.0, 1.0, 1.0],
                },
            })
        }
    };
    Ok(
        (colormap.is_some() || isolines.is_some() || lattice.is_some()).then_some(TextureSpec {
            colormap,
            isolines,
            lattice,
        }),
    )
}
