//! Scenes: the shared description ([`desc`]), its loaders (TOML here, Python dicts in the
//! bindings), located errors ([`errors`]) and the build into a traceable [`Scene<N>`].

pub mod animation;
pub mod build;
pub mod desc;
mod elevation;
pub mod errors;
mod fields;
pub mod mesh_file;
pub mod npz;
pub mod table;
mod transform;

pub use build::{Light, Material, Object, Scene};
pub use desc::SceneDesc;
pub use errors::PathError;
pub use mesh_file::MeshReader;

use crate::{with_dim, NdError, NdResult, MAX_DIM, MIN_DIM};
use errors::{friendly_message, line_col, span_of};
use std::path::{Path, PathBuf};

/// Declares [`AnyScene`], one variant per dimension of [`crate::supported_dims!`], and its
/// [`IntoAny`] conversions.
macro_rules! any_scene {
    (; $($n:literal $variant:ident),*) => {
        /// A scene of any supported dimension: the one place where a runtime `dim` becomes
        /// `Scene<N>` (see [`with_scene!`](crate::with_scene)).
        pub enum AnyScene {
            $(
                #[doc = concat!("A scene in R^", stringify!($n), ".")]
                $variant(Scene<$n>),
            )*
        }

        $(
            impl IntoAny for Scene<$n> {
                fn into_any(self) -> AnyScene {
                    AnyScene::$variant(self)
                }
            }
        )*
    };
}
crate::supported_dims!((any_scene));

/// Runs `$body` with `$s` bound to the `Scene<N>` inside an [`AnyScene`] (and `$N` to N).
#[macro_export]
macro_rules! with_scene {
    ($any:expr, $s:ident, $N:ident => $body:expr) => {
        $crate::supported_dims!(($crate::__with_scene_arms) $any, $s, $N, $body)
    };
}

/// The `match` of [`with_scene!`], one arm per [`AnyScene`] variant.
#[doc(hidden)]
#[macro_export]
macro_rules! __with_scene_arms {
    ($any:expr, $s:ident, $N:ident, $body:expr ; $($n:literal $variant:ident),*) => {{
        match $any {
            $(
                $crate::scene::AnyScene::$variant($s) => {
                    const $N: usize = $n;
                    $body
                }
            )*
        }
    }};
}

/// Where a description came from, to locate its errors.
pub enum Source<'a> {
    /// A TOML file (name, text).
    Toml { name: &'a str, text: &'a str },
    /// Anything without positions (a Python dict); errors are prefixed with this name.
    Unlocated(&'a str),
}

/// A scene description together with its source, ready to build.
pub struct Loaded {
    /// The description.
    pub desc: SceneDesc,
    /// Directory that relative mesh files are resolved against.
    pub base: Option<PathBuf>,
}

fn locate(
    src: &Source<'_>,
    root: Option<&toml::Spanned<toml::de::DeTable<'_>>>,
    e: PathError,
) -> NdError {
    let location = match (src, root) {
        (Source::Toml { name, text }, Some(root)) => {
            let (l, c) = line_col(text, span_of(root, &e.path).start);
            format!("{name}:{l}:{c}")
        }
        (Source::Toml { name, .. }, None) => name.to_string(),
        (Source::Unlocated(name), _) => name.to_string(),
    };
    NdError::Scene {
        location,
        path: e.path,
        message: e.message,
    }
}

/// Deserializes a description (or a part of one, such as the composite options), turning
/// serde errors into [`PathError`]s with field paths.
pub fn deserialize<'de, T, D>(de: D) -> Result<T, PathError>
where
    T: serde::Deserialize<'de>,
    D: serde::Deserializer<'de>,
    D::Error: std::fmt::Display,
{
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let path = if path == "." { String::new() } else { path };
        let inner = e.into_inner().to_string();
        // toml's own messages may carry a location block; keep the first line.
        let msg = inner
            .lines()
            .find(|l| !l.trim().is_empty() && !l.starts_with("TOML parse error"))
            .unwrap_or(&inner);
        PathError {
            message: friendly_message(msg.trim(), &path),
            path,
        }
    })
}

/// Parses TOML text and builds the scene; `name` locates errors (`name:line:col: path: msg`).
pub fn load_toml_str(
    text: &str,
    name: &str,
    base: Option<&Path>,
) -> NdResult<(SceneDesc, AnyScene)> {
    load_toml_with(text, name, base, None)
}

/// [`load_toml_str`], with `reader` reading mesh files of formats other than `.npz`.
pub fn load_toml_with(
    text: &str,
    name: &str,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> NdResult<(SceneDesc, AnyScene)> {
    let src = Source::Toml { name, text };
    let root = toml::de::DeTable::parse(text).map_err(|e| {
        let (l, c) = line_col(text, e.span().map_or(0, |s| s.start));
        NdError::Scene {
            location: format!("{name}:{l}:{c}"),
            path: String::new(),
            message: e.message().to_string(),
        }
    })?;
    let desc = deserialize(toml::de::Deserializer::from(root.clone()))
        .map_err(|e| locate(&src, Some(&root), e))?;
    let scene = build_any(&desc, base, reader).map_err(|e| locate(&src, Some(&root), e))?;
    Ok((desc, scene))
}

/// Reads a TOML scene file and builds it; mesh files resolve relative to its directory.
pub fn load_file(path: &Path) -> NdResult<(SceneDesc, AnyScene)> {
    load_file_with(path, None)
}

/// [`load_file`], with `reader` reading mesh files of formats other than `.npz`.
pub fn load_file_with(
    path: &Path,
    reader: Option<&dyn MeshReader>,
) -> NdResult<(SceneDesc, AnyScene)> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| NdError::Scene {
        location: name.clone(),
        path: String::new(),
        message: format!("cannot read: {e}"),
    })?;
    load_toml_with(&text, &name, path.parent(), reader)
}

/// Builds an already deserialized description, locating errors with `name` only.
pub fn build_desc(desc: &SceneDesc, name: &str, base: Option<&Path>) -> NdResult<AnyScene> {
    build_desc_with(desc, name, base, None)
}

/// [`build_desc`], with `reader` reading mesh files of formats other than `.npz`.
pub fn build_desc_with(
    desc: &SceneDesc,
    name: &str,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> NdResult<AnyScene> {
    build_any(desc, base, reader).map_err(|e| locate(&Source::Unlocated(name), None, e))
}

/// The description of frame `k` of the scene's `[animation]` (see [`animation`]); errors are
/// prefixed with `name`.
pub fn animation_frame(desc: &SceneDesc, k: u32, name: &str) -> NdResult<SceneDesc> {
    animation::frame_desc(desc, k).map_err(|e| locate(&Source::Unlocated(name), None, e))
}

/// Frame `k` of the `[animation]` of `desc` (built as `scene`) without a build: the frame's
/// description ([`animation_frame`]) and its scene, bit for bit the scene a build of that
/// description gives. When the animation moves the camera, the frame shares `scene`'s objects
/// and BVH ([`Scene::with_camera`]); when it moves objects, it shares `scene`'s BVHs, which
/// hold the objects in their own space, and moves the rays instead (`Scene::moved`). `None`
/// when there is no animation or the frame cannot share them: build the frame then.
pub fn reused_frame(
    desc: &SceneDesc,
    scene: &AnyScene,
    k: u32,
    name: &str,
) -> Option<NdResult<(SceneDesc, AnyScene)>> {
    let a = desc.animation.as_ref()?;
    let camera = matches!(&a.target, desc::AnimationTarget::Named(n) if n == "camera");
    let frame = match animation_frame(desc, k, name) {
        Ok(f) => f,
        Err(e) => return Some(Err(e)),
    };
    let built = if camera {
        with_scene!(scene, s, _N => s
            .with_camera(&frame.camera, frame.composite.as_ref())
            .map(IntoAny::into_any))
    } else {
        with_scene!(scene, s, _N => s.moved(&frame)?.map(IntoAny::into_any))
    };
    Some(
        built
            .map(|b| (frame, b))
            .map_err(|e| locate(&Source::Unlocated(name), None, e)),
    )
}

/// `desc` built by sharing `built`, the build of `old`, when the two descriptions differ at
/// most in their `[animation]` tables (a build only checks that table; it is checked here the
/// same way) and no object is read from a file (a build would read it again); `None`
/// otherwise: build `desc` then. `ndtrace.animate` gives a scene another table or frame count
/// this way without building it again.
pub fn reanimated(
    desc: &SceneDesc,
    old: &SceneDesc,
    built: &AnyScene,
    name: &str,
) -> Option<NdResult<AnyScene>> {
    if !desc.same_but_animation(old) || desc.objects.iter().any(desc::ObjectDesc::reads_file) {
        return None;
    }
    let checked = match &desc.animation {
        None => Ok(()),
        Some(a) => with_scene!(built, _s, N => animation::check::<N>(a, desc.objects.len())),
    };
    Some(
        checked
            .map(|()| with_scene!(built, s, _N => s.clone().into_any()))
            .map_err(|e| locate(&Source::Unlocated(name), None, e)),
    )
}

/// Serializes a description as TOML (the inverse of [`load_toml_str`] for the description).
pub fn to_toml(desc: &SceneDesc) -> NdResult<String> {
    toml::to_string(desc).map_err(|e| NdError::Value {
        arg: "scene".into(),
        message: e.to_string(),
    })
}

fn build_any(
    desc: &SceneDesc,
    base: Option<&Path>,
    reader: Option<&dyn MeshReader>,
) -> Result<AnyScene, PathError> {
    let built = with_dim!(desc.dim, N => build::build_with::<N>(desc, base, reader).map(|s| {
        // One conversion from Scene<N> to the enum, through a helper trait.
        <Scene<N> as IntoAny>::into_any(s)
    }));
    built.map_err(|_| {
        PathError::new(
            "dim",
            format!(
                "dimension {} is not supported: dim must be in {MIN_DIM}..={MAX_DIM}",
                desc.dim
            ),
        )
    })?
}

/// Wraps a `Scene<N>` in the matching [`AnyScene`] variant.
pub trait IntoAny {
    /// The wrapped scene.
    fn into_any(self) -> AnyScene;
}

impl AnyScene {
    /// The dimension N.
    pub fn dim(&self) -> usize {
        with_scene!(self, _s, N => N)
    }
    /// Warnings collected while building.
    pub fn warnings(&self) -> &[String] {
        with_scene!(self, s, _N => &s.warnings)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// The boundary of the regular N-simplex seen from +x_N, in dimension `dim`.
    fn simplex_scene(dim: usize) -> String {
        let axis = |k: usize, x: f64| -> String {
            let e: Vec<String> = (0..dim)
                .map(|i| if i == k { x.to_string() } else { "0".into() })
                .collect();
            format!("[{}]", e.join(", "))
        };
        let up: Vec<String> = (1..dim - 1).map(|k| axis(k, 1.0)).collect();
        format!(
            "dim = {dim}\n[camera]\nposition = {}\nlook_at = {}\nup = [{}]\nfov = 40\n\
             resolution = 2\n[[objects]]\nshape = \"simplex\"\n",
            axis(dim - 1, 4.0),
            axis(0, 0.0),
            up.join(", ")
        )
    }

    #[test]
    fn every_supported_dimension_has_its_scene_variant() {
        for &d in crate::dim::SUPPORTED_DIMS {
            let (_, scene) = load_toml_str(&simplex_scene(d), "simplex.toml", None).unwrap();
            assert_eq!(scene.dim(), d);
            // `with_scene!` binds the Scene<N> of the variant with N = d: its vectors have d
            // coordinates, and the simplex's boundary d + 1 facets.
            let (n, coords, facets) =
                with_scene!(&scene, s, N => (N, s.camera.position.len(), s.instances.len()));
            assert_eq!((n, coords, facets), (d, d, d + 1));
            // And back: the scene taken out of the enum goes into the same variant.
            let again = with_scene!(scene, s, _N => s.into_any());
            assert_eq!(again.dim(), d);
        }
        let e = err(&simplex_scene(3).replace("dim = 3", "dim = 9"));
        assert!(e.contains("dim must be in 2..=8"), "{e}");
    }

    const CUBE: &str = r#"
dim = 4
[camera]
position = [0, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = [8, 6, 4]

[[lights]]
type = "point"
position = [1, 2, 3, 4]
falloff = 3

[[objects]]
shape = "hypercube"
material = { color = [1, 0.5, 0.25], specular = [0.1, 0.2, 0.3], smooth = true }
transform = [{ scale = 0.5 }, { rotate = { plane = [0, 3], degrees = 30 } }, { translate = [0, 0, 0.5, 0] }]

[[objects]]
shape = "mesh"
vertices = [[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]
simplices = [[0, 1, 2, 3]]
"#;

    #[test]
    fn toml_round_trips_through_the_description() {
        let (desc, scene) = load_toml_str(CUBE, "cube.toml", None).unwrap();
        assert_eq!(scene.dim(), 4);
        let text = to_toml(&desc).unwrap();
        let (again, _) = load_toml_str(&text, "again.toml", None).unwrap();
        assert_eq!(desc, again);
        with_scene!(&scene, s, N => {
            assert_eq!(N, 4);
            assert_eq!(s.camera.numpy_shape(), vec![4, 6, 8]);
            assert_eq!(s.instances.len(), 48 + 1);
            assert_eq!(s.locate(48), (1, 0));
            assert_eq!(s.locate(47), (0, 47));
        });
    }

    fn err(text: &str) -> String {
        match load_toml_str(text, "scene.toml", None) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("expected an error for:\n{text}"),
        }
    }

    #[test]
    fn errors_name_file_line_column_and_field() {
        let bad = CUBE.replace("color = [1, 0.5, 0.25]", "color = [1, 0.5]");
        let line = bad
            .lines()
            .position(|l| l.contains("color = [1, 0.5]"))
            .unwrap()
            + 1;
        let col = bad.lines().nth(line - 1).unwrap().find("[1, 0.5]").unwrap() + 1;
        assert_eq!(
            err(&bad),
            format!(
                "scene.toml:{line}:{col}: objects[0].material.color: expected 3 numbers, got 2"
            )
        );
        let e = err(&CUBE.replace("shape = \"hypercube\"", "shape = \"hypercub\""));
        assert!(
            e.contains(
                "objects[0].shape: unknown shape \"hypercub\" (did you mean \"hypercube\"?)"
            ),
            "{e}"
        );
        let e = err(&CUBE.replace("falloff = 3", "falof = 3"));
        assert!(
            e.contains("lights[0]") && e.contains("did you mean \"falloff\""),
            "{e}"
        );
        let e = err(&CUBE.replace("simplices = [[0, 1, 2, 3]]", "simplices = [[0, 1, 2, 4]]"));
        assert!(
            e.contains("objects[1].simplices[0][3]: vertex index 4 out of range"),
            "{e}"
        );
        let e = err(&CUBE.replace("dim = 4", "dim = 9"));
        assert!(e.contains("dim") && e.contains("2..=8"), "{e}");
        let e = err(&CUBE.replace("resolution = [8, 6, 4]", "resolution = [8, 0, 4]"));
        assert!(
            e.contains("camera.resolution: axis 2 has zero cells"),
            "{e}"
        );
        let e = err(&CUBE.replace("resolution = [8, 6, 4]", "resolution = 100000000"));
        assert!(e.contains("camera.resolution") && e.contains("iB"), "{e}");
        let e = err(&CUBE.replace(
            "[[objects]]\nshape = \"mesh\"",
            "[[objects]]\nshape = \"mesh\"\nx = ]",
        ));
        assert!(e.starts_with("scene.toml:"), "{e}");
    }

    const ROTATED: &str = r#"
dim = 4
[camera]
position = [0, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = 4

[[objects]]
shape = "hypercube"
transform = [{ scale = 0.5 }, { rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }]
"#;

    fn vertices(text: &str) -> Vec<Vec<f64>> {
        let (_, scene) = load_toml_str(text, "scene.toml", None).unwrap();
        with_scene!(&scene, s, _N => s.objects[0].mesh.vertices.iter().map(|v| v.to_vec()).collect())
    }

    fn matrix_toml<const N: usize>(m: &crate::linalg::Matrix<N>) -> String {
        let rows: Vec<String> = m
            .iter()
            .map(|r| {
                format!(
                    "[{}]",
                    r.iter()
                        .map(|x| format!("{x:?}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
            .collect();
        format!("{{ matrix = [{}] }}", rows.join(", "))
    }

    fn assert_same_vertices(a: &[Vec<f64>], b: &[Vec<f64>]) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            for (p, q) in x.iter().zip(y) {
                assert!((p - q).abs() < 1e-15, "{x:?} vs {y:?}");
            }
        }
    }

    #[test]
    fn quaternion_and_rolling_rotations_equal_their_matrices() {
        use crate::rotation::{rolling_ball, so4_from_quaternions, RollingAngle};
        let m = so4_from_quaternions(&[0.6, 0.0, 0.8, 0.0], &[0.5, 0.5, 0.5, 0.5]);
        let by_matrix = ROTATED.replace(
            "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }",
            &matrix_toml(&m),
        );
        assert_same_vertices(&vertices(ROTATED), &vertices(&by_matrix));
        let rolled = ROTATED.replace(
            "quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]]",
            "rolling = [0.3, -0.2, 0.5], radius = 2, angle = \"arc\"",
        );
        let m = rolling_ball::<4>(&[0.3, -0.2, 0.5], 2.0, RollingAngle::Arc);
        let by_matrix = ROTATED.replace(
            "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }",
            &matrix_toml(&m),
        );
        assert_same_vertices(&vertices(&rolled), &vertices(&by_matrix));
        // The default angle is the course's c = R/D.
        let course = rolled.replace(", angle = \"arc\"", "");
        let m = rolling_ball::<4>(&[0.3, -0.2, 0.5], 2.0, RollingAngle::Course);
        let by_matrix = ROTATED.replace(
            "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }",
            &matrix_toml(&m),
        );
        assert_same_vertices(&vertices(&course), &vertices(&by_matrix));
        // Every form survives the TOML round trip.
        for text in [ROTATED.to_string(), rolled, course] {
            let (desc, _) = load_toml_str(&text, "a.toml", None).unwrap();
            let (again, _) = load_toml_str(&to_toml(&desc).unwrap(), "b.toml", None).unwrap();
            assert_eq!(desc, again);
        }
    }

    #[test]
    fn rotate_errors_name_the_field_and_its_place() {
        let bad = ROTATED.replace("[0.5, 0.5, 0.5, 0.5]", "[1, 0.75, 0, 0]");
        let line = bad.lines().position(|l| l.contains("[1, 0.75")).unwrap() + 1;
        let col = bad.lines().nth(line - 1).unwrap().find("[1, 0.75").unwrap() + 1;
        assert_eq!(
            err(&bad),
            format!(
                "scene.toml:{line}:{col}: objects[0].transform[1].rotate.quaternions[1]: not a unit quaternion (|p| = 1.25)"
            )
        );
        const STEP: &str =
            "{ rotate = { quaternions = [[0.6, 0, 0.8, 0], [0.5, 0.5, 0.5, 0.5]] } }";
        let cases: [(&str, &str, &[&str]); 9] = [
            ("[0.6, 0, 0.8, 0]", "[0.6, 0, 0.8]", &["rotate.quaternions[0]: expected 4 numbers"]),
            ("quaternions = [[0.6, 0, 0.8, 0], ", "quaternions = [", &["rotate.quaternions: expected [q, p]"]),
            ("] } }", "], plane = [0, 1], degrees = 3 } }", &["objects[0].transform[1].rotate.quaternions: give only one of plane, quaternions or rolling"]),
            ("] } }", "], radius = 1 } }", &["rotate.radius: \"radius\" goes with rolling, not with quaternions"]),
            (STEP, "{ rotate = { plane = [0, 1] } }", &["objects[0].transform[1].rotate: plane needs degrees"]),
            (STEP, "{ rotate = { rolling = [1, 2] , radius = 1 } }", &["rotate.rolling: expected N − 1 = 3 numbers (dim = 4), got 2"]),
            (STEP, "{ rotate = { rolling = [1, 2, 3] , radius = -1 } }", &["rotate.radius: must be a positive number, got -1"]),
            (STEP, "{ rotate = { rolling = [1, 2, 3] , radius = 1, angle = \"arcs\" } }", &["rotate.angle", "did you mean \"arc\""]),
            (STEP, "{ rotate = { } }", &["rotate: give one of plane"]),
        ];
        for (from, to, wants) in cases {
            let e = err(&ROTATED.replace(from, to));
            for want in wants {
                assert!(e.contains(want), "{to}: {e}");
            }
        }
        let three = ROTATED
            .replace("dim = 4", "dim = 3")
            .replace("[0, 0, 0, 5]", "[0, 0, 5]")
            .replace("look_at = [0, 0, 0, 0]", "look_at = [0, 0, 0]")
            .replace("up = [[0, 1, 0, 0], [0, 0, 1, 0]]", "up = [[0, 1, 0]]");
        let e = err(&three);
        assert!(
            e.contains("rotate.quaternions: quaternions = [q, p] give a 4D rotation, but dim = 3"),
            "{e}"
        );
    }

    #[test]
    fn an_array_field_is_the_inline_field_with_the_same_values() {
        let text = "dim = 4\n[camera]\nposition = [0.6, 0.8, 1.0, 3.0]\nlook_at = [0, 0, 0, 0]\n\
                    up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 6\n[[objects]]\n\
                    shape = \"elevation\"\nfield = [[[0, 1, 2], [1, 0, 3]], [[2, 2, 0], [0.5, 1, 1]]]\n";
        let (inline, built) = load_toml_str(text, "f.toml", None).unwrap();
        let values = vec![0.0, 1.0, 2.0, 1.0, 0.0, 3.0, 2.0, 2.0, 0.0, 0.5, 1.0, 1.0];
        let mut array = inline.clone();
        array.objects[0].field = Some(desc::FieldDesc::Array(
            desc::Grid::new([2, 2, 3], values.clone()).unwrap(),
        ));
        assert_eq!(array, inline);
        assert_eq!(inline, array);
        assert_eq!(to_toml(&array).unwrap(), to_toml(&inline).unwrap());
        let mut other = values;
        other[4] = 0.25;
        let mut changed = inline.clone();
        changed.objects[0].field = Some(desc::FieldDesc::Array(
            desc::Grid::new([2, 2, 3], other).unwrap(),
        ));
        assert!(changed != inline && changed != array);
        assert!(desc::Grid::new([2, 2, 2], vec![0.0; 7]).is_none());
        assert!(desc::Grid::new([1 << 40, 1 << 40, 0], vec![]).is_none());
        // Masked (NaN) values equal themselves, in copies and across the two forms.
        let mut masked = inline.clone();
        if let Some(desc::FieldDesc::Inline(x)) = &mut masked.objects[0].field {
            x[1][0][2] = f64::NAN;
        }
        let mut masked_array = masked.clone();
        let mut v = vec![0.0, 1.0, 2.0, 1.0, 0.0, 3.0, 2.0, 2.0, 0.0, 0.5, 1.0, 1.0];
        v[8] = f64::NAN;
        masked_array.objects[0].field = Some(desc::FieldDesc::Array(
            desc::Grid::new([2, 2, 3], v).unwrap(),
        ));
        assert_eq!(masked_array, masked_array.clone());
        assert_eq!(masked_array, masked);
        assert_ne!(masked_array, inline);
        // Empty axes write as empty lists (the build refuses them; writing must not panic).
        let empty = desc::Grid::new([2, 0, 3], vec![]).unwrap();
        let mut text_empty = inline.clone();
        text_empty.objects[0].field = Some(desc::FieldDesc::Array(empty));
        assert!(to_toml(&text_empty).unwrap().contains("field = [[], []]"));
        let from_array = build_desc(&array, "f", None).unwrap();
        let depth = |s: &AnyScene| with_scene!(s, s, _N => crate::render::trace(s, &Default::default()).unwrap().depth);
        assert_eq!(depth(&from_array), depth(&built));
    }

    #[test]
    fn array_meshes_build_as_their_inline_lists_and_errors_name_the_row() {
        let text = "dim = 3\n[camera]\nposition = [0.5, 0.7, 3.0]\nlook_at = [0, 0, 0]\n\
                    up = [0, 1, 0]\nfov = 50\nresolution = 8\n[[objects]]\nshape = \"mesh\"\n\
                    vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0], [0, 0, 1]]\n\
                    simplices = [[0, 1, 2], [0, 1, 3], [1, 2, 3], [2, 0, 3]]\n\
                    values = [0, 1, 2, 3]\nmaterial = { colormap = \"viridis\" }\n";
        let (inline, built) = load_toml_str(text, "m.toml", None).unwrap();
        let v = vec![
            -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let s = vec![0i64, 1, 2, 0, 1, 3, 1, 2, 3, 2, 0, 3];
        let with = |v: Vec<f64>, width: usize, s: Vec<i64>| {
            let mut d = inline.clone();
            d.objects[0].vertices = Some(desc::Rows::Array(desc::Table::new(width, v).unwrap()));
            d.objects[0].simplices = Some(desc::Rows::Array(desc::Table::new(3, s).unwrap()));
            d.objects[0].values = Some(desc::Column::Array(vec![0.0, 1.0, 2.0, 3.0].into()));
            d
        };
        let array = with(v.clone(), 3, s.clone());
        assert_eq!(array, inline);
        assert_eq!(inline, array);
        assert_eq!(to_toml(&array).unwrap(), to_toml(&inline).unwrap());
        let from_array = build_desc(&array, "m", None).unwrap();
        let trace = |s: &AnyScene| {
            with_scene!(s, s, _N => {
                let r = crate::render::trace(s, &Default::default()).unwrap();
                (r.depth, r.rgba)
            })
        };
        let (d0, c0) = trace(&built);
        assert!(d0.iter().any(|d| d.is_finite()));
        assert_eq!((d0, c0), trace(&from_array));
        // A changed coordinate differs; errors name the element, as for lists.
        let mut moved = v.clone();
        moved[11] = 0.5;
        assert_ne!(with(moved, 3, s.clone()), inline);
        let err = |d: &SceneDesc| build_desc(d, "m", None).err().unwrap().to_string();
        let mut out_of_range = s.clone();
        out_of_range[7] = 4;
        assert!(err(&with(v.clone(), 3, out_of_range))
            .contains("objects[0].simplices[2][1]: vertex index 4 out of range"),);
        let mut nan = v.clone();
        nan[4] = f64::NAN;
        assert!(err(&with(nan, 3, s.clone())).contains("objects[0].vertices[1][1]: non-finite"));
        let wide = with(vec![0.0; 8], 4, s);
        assert!(err(&wide).contains("objects[0].vertices[0]: expected 3 numbers (dim = 3), got 4"));
    }

    /// The bits of a scene's retina: colour, depth, normals, object and primitive ids.
    type Bits = (Vec<u32>, Vec<u32>, Vec<u32>, Vec<i32>, Vec<i64>);

    /// The [`Bits`] of the retina `s` traces.
    fn retina_bits(s: &AnyScene) -> Bits {
        let r = with_scene!(s, s, _N => crate::render::trace(s, &Default::default()).unwrap());
        let f = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        (
            f(&r.rgba),
            f(&r.depth),
            f(&r.normal),
            r.object_id,
            r.primitive_id,
        )
    }

    #[test]
    fn camera_frames_share_the_bvh_and_trace_as_the_frames_built_anew() {
        let text = |target: &str, extra: &str| {
            format!(
                "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
                 up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = [14, 12, 10]\n\
                 [[lights]]\ntype = \"point\"\nposition = [2, 2, 1, 2]\n\
                 [[objects]]\nshape = \"hypercube\"\ntransform = [{{ scale = 0.6 }}]\n\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 2\n\
                 transform = [{{ scale = 0.3 }}, {{ translate = [0.5, 0.4, 0.2, 0.3] }}]\n\
                 [render]\nsamples = 2\nshadows = true\ncull_backfaces = true\n{extra}\
                 [animation]\nframes = 4\ntarget = {target}\n\
                 sweep = {{ plane = [0, 3], degrees = [0, 120] }}\n"
            )
        };
        let (desc, scene) = load_toml_str(&text("\"camera\"", ""), "cam.toml", None).unwrap();
        let bits = retina_bits;
        let mut frames = Vec::new();
        for k in 0..4 {
            let (frame, shared) = reused_frame(&desc, &scene, k, "cam.toml").unwrap().unwrap();
            assert_eq!(frame, animation_frame(&desc, k, "cam.toml").unwrap());
            let built = build_any(&frame, None, None).unwrap();
            let traced = bits(&shared);
            assert_eq!(traced, bits(&built), "frame {k}");
            match (&scene, &shared) {
                (AnyScene::D4(a), AnyScene::D4(b)) => {
                    assert!(
                        (a.instances.trees().iter().zip(b.instances.trees()))
                            .all(|(x, y)| Arc::ptr_eq(x, y))
                            && Arc::ptr_eq(&a.objects, &b.objects)
                    )
                }
                _ => panic!("dim 4"),
            }
            frames.push(traced);
        }
        // The camera moves: the frames differ.
        assert!(frames[1..].iter().all(|f| *f != frames[0]));
        // Frames that do not exist are refused.
        let err = reused_frame(&desc, &scene, 4, "cam.toml")
            .unwrap()
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("animation.frames"), "{err}");
    }

    #[test]
    fn another_animation_table_shares_the_build() {
        let text = "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
                    up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 8\n\
                    [[objects]]\nshape = \"hypercube\"\n";
        let (old, built) = load_toml_str(text, "a.toml", None).unwrap();
        let mut desc = old.clone();
        let table = "[animation]\nframes = 5\ntarget = [0]\nsweep = { plane = [0, 3], degrees = [0, 90] }\n";
        desc.animation = load_toml_str(&format!("{text}{table}"), "a.toml", None)
            .unwrap()
            .0
            .animation;
        let shared = reanimated(&desc, &old, &built, "a.toml").unwrap().unwrap();
        match (&built, &shared) {
            (AnyScene::D4(a), AnyScene::D4(b)) => {
                assert!(
                    (a.instances.trees().iter().zip(b.instances.trees()))
                        .all(|(x, y)| Arc::ptr_eq(x, y))
                        && Arc::ptr_eq(&a.objects, &b.objects)
                )
            }
            _ => panic!("dim 4"),
        }
        assert_eq!(
            retina_bits(&shared),
            retina_bits(&build_any(&desc, None, None).unwrap())
        );
        // The table is checked as a build checks it.
        let mut bad = desc.clone();
        bad.animation.as_mut().unwrap().target = desc::AnimationTarget::Objects(vec![3]);
        let err = reanimated(&bad, &old, &built, "a.toml")
            .unwrap()
            .err()
            .unwrap();
        let want = build_desc(&bad, "a.toml", None).err().unwrap().to_string();
        assert_eq!(err.to_string(), want);
        assert!(want.contains("animation.target[0]"), "{want}");
        // Anything else changed, or an object read from a file: build anew.
        let mut other = desc.clone();
        other.camera.fov = Some(40.0);
        assert!(reanimated(&other, &old, &built, "a.toml").is_none());
        let mut filed = old.clone();
        filed.objects[0].file = Some("cube.npz".into());
        assert!(reanimated(&filed, &filed, &built, "a.toml").is_none());
    }

    #[test]
    fn object_frames_share_the_bvh_and_trace_as_the_frames_built_anew() {
        // Frames of an animation that moves objects: the base scene's trees reached through
        // the frames' transforms (flat cells included, in 5D) trace bit for bit as the
        // frame's own build; shadows, convexity certificates and culling included; the whole
        // scene, or one object; objects in their own tree or sharing the untransformed
        // objects' tree (with `scaled = false` the hypercube has no transform of its own), a
        // transform that reverses handedness (`mirror`).
        fn check<const N: usize>(target: &str, scaled: bool, mirror: bool, instance_min: usize) {
            let axis = crate::testutil::unit_toml::<N>;
            let up: Vec<String> = (1..N - 1).map(|k| axis(k, 1.0)).collect();
            let position: Vec<String> = (0..N)
                .map(|i| format!("{:?}", 0.6 + 0.3 * i as f64))
                .collect();
            let text = format!(
                "dim = {N}\n[camera]\nposition = [{}]\nlook_at = {}\nup = [{}]\nfov = 50\n\
                 resolution = {}\n[[lights]]\ntype = \"point\"\nposition = {}\n\
                 [[objects]]\nshape = \"hypercube\"\n{}\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 1\nmaterial = {{ smooth = true }}\n\
                 transform = [{{ scale = 0.3 }}, {{ translate = {} }}]\n\
                 [[objects]]\nshape = \"mesh\"\nvertices = [{}]\nsimplices = [[0, 0, {}]]\n\
                 [render]\nsamples = 2\nshadows = true\ncull_backfaces = true\n\
                 [animation]\nframes = 4\ntarget = {target}\n\
                 sweep = {{ plane = [0, {}], degrees = [0, 120] }}\n",
                position.join(", "),
                axis(0, 0.0),
                up.join(", "),
                if N == 4 { 12 } else { 6 },
                axis(N - 1, 2.0),
                match (scaled, mirror) {
                    (false, _) => String::new(),
                    (true, false) => "transform = [{ scale = 0.6 }]\n".into(),
                    (true, true) => format!(
                        "transform = [{{ scale = [-0.6{}] }}]\n",
                        ", 0.6".repeat(N - 1)
                    ),
                },
                axis(0, 0.7),
                (0..N).map(|k| axis(k, 1.0 + k as f64)).collect::<Vec<_>>().join(", "),
                (1..N - 1).map(|k| k.to_string()).collect::<Vec<_>>().join(", "),
                N - 1
            );
            let (desc, _) = load_toml_str(&text, "obj.toml", None).unwrap();
            let build = |d: &SceneDesc| {
                let morton = crate::accel::MORTON_MIN;
                with_dim!(d.dim, M => {
                    let s = super::build::build_using::<M>(d, None, None, morton, instance_min);
                    <Scene<M> as IntoAny>::into_any(s.unwrap())
                })
                .unwrap()
            };
            let scene = build(&desc);
            // The base scene's feature edges: the frames share its objects' ridges, and keep
            // the edges of the objects they do not move.
            let unmoved: Vec<usize> = match target {
                "[1]" => vec![0, 2],
                "[0]" => vec![1, 2],
                _ => vec![],
            };
            let ridges = with_scene!(&scene, s, _N => {
                crate::edges::edge_segments(s, 20.0).unwrap();
                s.edge_cache.contents().1
            });
            assert_eq!(ridges.len(), 3);
            let bits = retina_bits;
            let mut frames = Vec::new();
            for k in 0..4 {
                let (frame, reused) = reused_frame(&desc, &scene, k, "obj.toml").unwrap().unwrap();
                let built = build(&frame);
                // The frame traces the base scene's trees (none is changed); objects traced in
                // world space (fewer than `instance_min` simplices) get a tree built anew
                // when one of them moves.
                with_scene!(&scene, a, _N => with_scene!(&reused, b, _M => {
                    for o in 0..3 {
                        let (x, y) = (a.instances.tree(o), b.instances.tree(o));
                        let own = a.objects[o].mesh.simplices.len() >= instance_min;
                        let same = std::ptr::addr_eq(Arc::as_ptr(x), Arc::as_ptr(y));
                        assert_eq!(same, own || k == 0, "N={N} {target} frame {k} object {o}");
                    }
                }));
                let traced = bits(&reused);
                assert_eq!(traced, bits(&built), "N={N} {target} frame {k}");
                // Frame 0 turns by 0°: every object keeps its vertices and its edges.
                let kept = if k == 0 {
                    vec![0, 1, 2]
                } else {
                    unmoved.clone()
                };
                match (&reused, &built) {
                    (AnyScene::D4(a), AnyScene::D4(b)) => check_same(a, b, &kept, &ridges),
                    (AnyScene::D5(a), AnyScene::D5(b)) => check_same(a, b, &kept, &ridges),
                    _ => panic!("dim"),
                }
                frames.push(traced);
            }
            assert!(
                frames[1..].iter().all(|f| *f != frames[0]),
                "the objects move"
            );
        }
        fn check_same<const N: usize>(
            reused: &Scene<N>,
            built: &Scene<N>,
            unmoved: &[usize],
            ridges: &[(usize, usize)],
        ) {
            // Feature edges from the shared ridges (none found again) and the moved
            // vertices: bit for bit those of the frame built anew.
            assert_eq!(
                reused.edge_cache.contents(),
                (unmoved.to_vec(), ridges.to_vec())
            );
            let edges = crate::edges::edge_segments(reused, 20.0).unwrap();
            assert_eq!(edges, crate::edges::edge_segments(built, 20.0).unwrap());
            assert!(edges.iter().any(|e| e.object == 0) && edges.iter().any(|e| e.object == 1));
            assert_eq!(reused.edge_cache.contents().1, ridges, "the ridges fit");
            assert_eq!(reused.instances.cell_count(), built.instances.cell_count());
            assert_eq!(reused.extent.to_bits(), built.extent.to_bits());
            assert_eq!(reused.skipped_degenerate, built.skipped_degenerate);
            for (a, b) in reused.objects.iter().zip(built.objects.iter()) {
                assert_eq!(a.convex, b.convex);
                assert_eq!(a.mesh, b.mesh);
            }
            for g in 0..built.simplex_count() as u32 {
                assert_eq!(reused.flat_normal(g), built.flat_normal(g));
            }
        }
        for min in [1, super::build::INSTANCE_MIN] {
            check::<4>("\"objects\"", true, false, min);
            check::<4>("[1]", true, false, min);
            check::<4>("[0]", false, false, min);
            check::<4>("\"objects\"", true, true, min);
            check::<5>("\"objects\"", true, false, min);
        }
    }

    #[test]
    fn frames_moving_small_objects_beside_a_large_one_trace_as_built_anew() {
        // A large untransformed sphere (24,576 tetrahedra) and a small hypercube share the
        // world-space tree; frames that move the hypercube give it a tree built anew, and the
        // shared tree's stale copy of it must not be seen; with "objects" the sphere is
        // traced through its map in the same tree.
        for target in ["[1]", "\"objects\""] {
            let text = format!(
                "dim = 4\n[camera]\nposition = [0.6, 0.9, 1.3, 3.5]\nlook_at = [0, 0, 0, 0]\n\
                 up = [[0, 1, 0, 0], [0, 0, 1, 0]]\nfov = 50\nresolution = 14\n\
                 [[lights]]\ntype = \"point\"\nposition = [2, 2, 1, 2]\n\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 3\n\
                 [[objects]]\nshape = \"hypercube\"\n\
                 transform = [{{ scale = 0.3 }}, {{ translate = [0.9, 0.2, 0.3, 0.5] }}]\n\
                 [render]\nshadows = true\n\
                 [animation]\nframes = 3\ntarget = {target}\n\
                 sweep = {{ plane = [0, 3], degrees = [0, 90] }}\n"
            );
            let (desc, scene) = load_toml_str(&text, "mix.toml", None).unwrap();
            for k in 0..3 {
                let (frame, reused) = reused_frame(&desc, &scene, k, "mix.toml").unwrap().unwrap();
                let built = build_any(&frame, None, None).unwrap();
                assert_eq!(
                    retina_bits(&reused),
                    retina_bits(&built),
                    "{target} frame {k}"
                );
                if let (AnyScene::D4(a), AnyScene::D4(b)) = (&reused, &built) {
                    assert_eq!(a.instances.len(), b.instances.len());
                    assert_eq!(a.skipped_degenerate, b.skipped_degenerate);
                }
            }
        }
    }

    #[test]
    fn objects_in_their_own_space_trace_as_their_meshes_moved_into_world_space() {
        // Independent reference: each transformed object given instead as a mesh of its
        // world-space vertices (no transform: traced as before instancing, in world space).
        // Shear, reflection, non-uniform scale and translation, with shadows and culling.
        fn check<const N: usize>() {
            let axis = crate::testutil::unit_toml::<N>;
            let list = |v: Vec<String>| v.join(", ");
            let up = list((1..N - 1).map(|k| axis(k, 1.0)).collect());
            let position = list(
                (0..N)
                    .map(|i| format!("{:?}", 0.7 + 0.4 * i as f64))
                    .collect(),
            );
            let head = format!(
                "dim = {N}\n[camera]\nposition = [{position}]\nlook_at = {}\nup = [{up}]\n\
                 fov = 45\nresolution = {}\n[[lights]]\ntype = \"point\"\nposition = [{}]\n\
                 [render]\nshadows = true\ncull_backfaces = true\n",
                axis(0, 0.0),
                if N == 3 {
                    48
                } else if N == 4 {
                    20
                } else {
                    8
                },
                list(
                    (0..N)
                        .map(|i| format!("{:?}", 2.0 - 0.5 * i as f64))
                        .collect()
                ),
            );
            // A hypercube sheared and mirrored, and a sphere mirrored, squashed and moved in front
            // of it.
            let shear = list(
                (0..N)
                    .map(|i| {
                        let row = (0..N).map(|j| {
                            let x = match j {
                                _ if i == j => [-0.5, 0.5][i.min(1)],
                                _ if j == i + 1 => 0.2,
                                _ => 0.0,
                            };
                            format!("{x:?}")
                        });
                        format!("[{}]", row.collect::<Vec<_>>().join(", "))
                    })
                    .collect(),
            );
            let squash = list(
                (0..N)
                    .map(|i| format!("{:?}", [-0.3, 0.4, 0.25][i % 3]))
                    .collect(),
            );
            let moved = format!(
                "[[objects]]\nshape = \"hypercube\"\ntransform = [{{ matrix = [{shear}] }}]\n\
                 [[objects]]\nshape = \"sphere\"\nsubdivisions = 1\n\
                 transform = [{{ scale = [{squash}] }}, {{ translate = [{}] }}]\n",
                list(
                    (0..N)
                        .map(|i| format!("{:?}", 0.35 + 0.1 * i as f64))
                        .collect()
                ),
            );
            let parse = |text: &str| {
                let (desc, _) = load_toml_str(text, "t.toml", None).unwrap();
                let morton = crate::accel::MORTON_MIN;
                super::build::build_using::<N>(&desc, None, None, morton, 1).unwrap()
            };
            let s = &parse(&format!("{head}{moved}"));
            // The reference: the world-space meshes (simplices in the order the build gave
            // them, mirrored ones swapped) as untransformed mesh objects.
            let mut world = head.clone();
            for o in s.objects.iter() {
                let v: Vec<String> = o.mesh.vertices.iter().map(|v| format!("{v:?}")).collect();
                let t: Vec<String> = o.mesh.simplices.iter().map(|t| format!("{t:?}")).collect();
                world += &format!(
                    "[[objects]]\nshape = \"mesh\"\nvertices = [{}]\nsimplices = [{}]\n",
                    v.join(", "),
                    t.join(", ")
                );
            }
            let w = &parse(&world);
            assert_eq!(
                s.instances.instance_count(),
                2,
                "N={N}: each object in its own space"
            );
            assert_eq!(w.instances.instance_count(), 1);
            // The mirrored, sheared hypercube is known convex, its certificate found in its own
            // space (the reference's mesh of coplanar simplices need not pass); the sphere's is
            // the reference's.
            assert_eq!(
                s.objects[0].convex,
                Some(true),
                "N={N}: the hypercube's certificate"
            );
            assert_eq!(
                s.objects[1].convex, w.objects[1].convex,
                "N={N}: the sphere's"
            );
            for g in 0..s.simplex_count() as u32 {
                let (a, b) = (s.flat_normal(g), w.flat_normal(g));
                let d = (0..N).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
                // (Each rounded to f32 in its own space.)
                assert!(d < 1e-6, "N={N} simplex {g}: normals {a:?} and {b:?}");
            }
            let opts = Default::default();
            let a = crate::render::trace(s, &opts).unwrap();
            let b = crate::render::trace(w, &opts).unwrap();
            let cells = a.object_id.len();
            let same: Vec<usize> = (0..cells)
                .filter(|&c| {
                    a.object_id[c] == b.object_id[c] && a.primitive_id[c] == b.primitive_id[c]
                })
                .collect();
            assert!(
                same.len() as f64 >= 0.99 * cells as f64,
                "N={N}: {} of {cells} cells hit the same simplex",
                same.len()
            );
            let hits = same.iter().filter(|&&c| a.object_id[c] >= 0).count();
            assert!(
                hits >= 50,
                "N={N}: the objects fill {hits} of {cells} cells"
            );
            let mut shaded_apart = 0;
            for &c in &same {
                let close = |x: f32, y: f32, tol: f32| (x - y).abs() <= tol * (1.0 + x.abs());
                if a.object_id[c] >= 0 {
                    assert!(close(a.depth[c], b.depth[c], 1e-5), "N={N} cell {c}: depth");
                }
                for i in 0..N {
                    assert!(close(a.normal[c * N + i], b.normal[c * N + i], 1e-5));
                }
                // A shadow ray grazing an edge may decide otherwise.
                if (0..4).any(|k| !close(a.rgba[c * 4 + k], b.rgba[c * 4 + k], 1e-4)) {
                    shaded_apart += 1;
                }
            }
            assert!(
                shaded_apart * 100 <= cells,
                "N={N}: {shaded_apart} cells shaded apart"
            );
        }
        check::<3>();
        check::<4>();
        check::<5>();
    }
}
