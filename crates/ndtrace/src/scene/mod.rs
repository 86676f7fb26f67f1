//! Scenes: the shared description ([`desc`]), its loaders (TOML here, Python dicts in the
//! bindings), located errors ([`errors`]) and the build into a traceable [`Scene<N>`].

pub mod animation;
pub mod build;
mod camera;
pub mod clip;
pub mod desc;
mod elevation;
pub mod errors;
mod fields;
mod frames;
mod lights;
mod material;
pub mod mesh_file;
pub mod npz;
mod objects;
pub mod slice;
pub mod table;
mod transform;

pub use build::Scene;
pub use desc::SceneDesc;
pub use errors::PathError;
pub use lights::Light;
pub use material::{Material, DEPTH_COLORMAP};
pub use mesh_file::MeshReader;
pub use objects::{Object, MAX_GENERATED_SIMPLICES};

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

/// The description of the (N−1)-dimensional slice of `desc` (built as `scene`) by the
/// hyperplane `cut` ([`slice::slice_desc`]); `None` for `cut` takes the scene's `[slice]`.
/// Errors are prefixed with `name` and name `slice.normal` or `slice.offset`.
pub fn slice_scene(
    desc: &SceneDesc,
    scene: &AnyScene,
    cut: Option<&desc::SliceDesc>,
    name: &str,
) -> NdResult<SceneDesc> {
    let fail = |e| locate(&Source::Unlocated(name), None, e);
    let Some(cut) = cut.or(desc.slice.as_ref()) else {
        return Err(fail(PathError::new(
            "slice",
            "the scene has no [slice] table",
        )));
    };
    if desc.dim < 3 {
        return Err(fail(PathError::new(
            "slice",
            format!(
                "slices need dim ≥ 3 (their dimension is dim − 1), got dim = {}",
                desc.dim
            ),
        )));
    }
    with_scene!(scene, s, _N => slice::slice_desc(desc, s, cut, "slice")).map_err(fail)
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
mod tests;
