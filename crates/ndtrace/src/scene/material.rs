//! Materials and textures: a `material` table checked and resolved to RGB coefficients
//! (course notes, Part II(B) "4D Shading": the Lambert and Blinn–Phong terms), with its
//! texture keys (colormap, isolines, cubic lattice: Part II(B)'s cues for 3D fields).

use super::desc::{ColorBy, MaterialDesc};
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
    /// Colour varying over the object: colormap, isolines, lattice, colour by cell or depth.
    pub texture: Option<crate::texture::TextureSpec>,
    /// Colour by structure (`"object"` is resolved by the build: the palette's colour of the
    /// object's index replaces `color`).
    pub color_by: Option<ColorBy>,
    /// The qualitative palette of `color_by` and of edges coloured by direction.
    pub palette: crate::texture::Palette,
}

/// The colormap of `color_by = "depth"` when a material names none: warm near the eye, cool
/// far from it, as the course's depth cueing.
pub const DEPTH_COLORMAP: &str = "coolwarm_r";

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
        color_by: m.color_by,
        palette: palette(m, path)?,
    })
}

/// The material's `palette` (default [`DEFAULT_PALETTE`](crate::texture::palette::DEFAULT_PALETTE)).
fn palette(m: &MaterialDesc, path: &str) -> R<crate::texture::Palette> {
    use crate::texture::palette;
    let name = m.palette.as_deref().unwrap_or(palette::DEFAULT_PALETTE);
    palette::get(name).ok_or_else(|| {
        PathError::new(
            format!("{path}.palette"),
            format!(
                "unknown palette \"{name}\" (known: {})",
                palette::names().join(", ")
            ),
        )
    })
}

/// The texture keys of a material (`colormap`, `range`, `isolines`, `lattice`).
fn texture_spec(m: &MaterialDesc, path: &str) -> R<Option<crate::texture::TextureSpec>> {
    use crate::texture::{colormap, Isolines, Lattice, TextureSpec};
    let by_depth = m.color_by == Some(ColorBy::Depth);
    if m.colormap.is_some() && matches!(m.color_by, Some(ColorBy::Cell | ColorBy::Object)) {
        return Err(PathError::new(
            format!("{path}.color_by"),
            "colormap and color_by both set the colour: give one (color_by = \"depth\" takes the colormap for its ramp)",
        ));
    }
    let range = match &m.range {
        None => None,
        Some(r) => match r[..] {
            [lo, hi] if lo.is_finite() && hi.is_finite() && hi != lo => Some([lo, hi]),
            _ => {
                return Err(PathError::new(
                    format!("{path}.range"),
                    format!("expected [low, high], two different finite numbers, got {r:?}"),
                ))
            }
        },
    };
    let colormap = match (&m.colormap, by_depth) {
        (None, true) => Some((
            colormap::get(DEPTH_COLORMAP).expect("the depth colormap is shipped"),
            range,
        )),
        (None, false) => {
            if m.range.is_some() {
                return Err(PathError::new(
                    format!("{path}.range"),
                    "\"range\" sets the values at a colormap's ends: give material.colormap",
                ));
            }
            None
        }
        (Some(name), _) => {
            let map = colormap::get(name).ok_or_else(|| {
                PathError::new(
                    format!("{path}.colormap"),
                    format!(
                        "unknown colormap \"{name}\" (known: {}; \"_r\" reverses one)",
                        colormap::names().join(", ")
                    ),
                )
            })?;
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
    let by_cell = match m.color_by {
        Some(ColorBy::Cell) => Some(palette(m, path)?),
        _ => None,
    };
    Ok(
        (colormap.is_some() || isolines.is_some() || lattice.is_some() || by_cell.is_some())
            .then_some(TextureSpec {
                colormap,
                isolines,
                lattice,
                by_cell,
                by_depth,
            }),
    )
}
