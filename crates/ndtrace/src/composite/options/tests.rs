use super::*;
use crate::scene::{load_toml_str, to_toml};

/// Every key set to a value other than its default, in the order of the fields.
const EVERY_KEY: &str = r#"mode = "slices"
azimuth = -10.5
elevation = 45.0
distance = 2.5
zoom = 1.5
projection = "orthographic"
size = [320, 200]
opacity = 0.25
step = 0.75
rays_per_cell = 3
depth_cue = 0.5
axis = 2
background = [0.1, 0.2, 0.3]
stages = [[2.0, 4.0]]
strip_height = 7
labels = false
fit = false
crease_angle = 35.0
edges = false
edge_width = 3.5
edge_color = [0.5, 0.25, 1.0]
hidden_edges = "faint"
layout = "stereo"
section = [0.5, -0.25, 0.0]
stereo_angle = 4.0
turntable = 12
legend = true
axes = false
axes_frame = [[0.0, 1.0], [-1.0, 0.0]]
title = "A title"
edge_color_by = "direction"
samples = 9
detail = "retina"

[cutaway]
shape = "sphere"
center = [0.0, 0.25, 0.0]
radius = 0.5

[cubes]
size = 0.5
"#;

#[test]
fn every_key_sets_its_own_field_and_is_written_back() {
    let o: CompositeOptions = toml::from_str(EVERY_KEY).unwrap();
    let expect = CompositeOptions {
        mode: CompositeMode::Slices,
        azimuth: -10.5,
        elevation: 45.0,
        distance: 2.5,
        zoom: 1.5,
        projection: Projection::Orthographic,
        size: (320, 200),
        opacity: 0.25,
        step: 0.75,
        rays_per_cell: 3,
        depth_cue: 0.5,
        axis: 2,
        background: [0.1, 0.2, 0.3],
        stages: vec![(2.0, 4.0)],
        strip_height: 7,
        labels: false,
        fit: false,
        crease_angle: 35.0,
        edges: false,
        edge_width: 3.5,
        edge_color: Some([0.5, 0.25, 1.0]),
        hidden_edges: HiddenEdges::Faint,
        layout: ViewLayout::Stereo,
        section: [0.5, -0.25, 0.0],
        stereo_angle: 4.0,
        turntable: 12,
        legend: Toggle::On,
        axes: Toggle::Off,
        axes_frame: Some(vec![vec![0.0, 1.0], vec![-1.0, 0.0]]),
        title: Some("A title".into()),
        edge_color_by: EdgeColorBy::Direction,
        cutaway: Some(Cutaway::Sphere {
            center: [0.0, 0.25, 0.0],
            radius: 0.5,
        }),
        cubes: Some(crate::composite::Cubes { size: 0.5 }),
        samples: 9,
        detail: Detail::Retina,
        given: GivenKeys::ALL,
    };
    assert_eq!(o, expect);
    assert_eq!(toml::to_string(&o).unwrap(), EVERY_KEY);
    // One line per key in the fields' order, the table-valued `cutaway` and `cubes` last as
    // their own sections.
    let mut keys: Vec<&str> = EVERY_KEY
        .lines()
        .take_while(|l| !l.is_empty())
        .map(|l| &l[..l.find(' ').unwrap()])
        .collect();
    keys.extend(["cutaway", "cubes"]);
    let tables = ["cutaway", "cubes"];
    let mut fields: Vec<&str> = CompositeOptions::KEYS
        .iter()
        .copied()
        .filter(|k| !tables.contains(k))
        .collect();
    fields.extend(tables);
    assert_eq!(keys, fields);
    assert!(CompositeOptions::KEYS.iter().all(|k| o.given.has(k)));
}

#[test]
fn a_table_is_written_back_with_the_keys_it_gave() {
    // A given default (mode = "volume") stays; the order is the fields' order.
    let o: CompositeOptions = toml::from_str("opacity = 0.6\nmode = \"volume\"\n").unwrap();
    assert_eq!((o.mode, o.opacity), (CompositeMode::Volume, 0.6));
    assert!(o.given.has("mode") && o.given.has("opacity") && !o.given.has("azimuth"));
    let text = toml::to_string(&o).unwrap();
    assert_eq!(text, "mode = \"volume\"\nopacity = 0.6\n");
    assert_eq!(toml::from_str::<CompositeOptions>(&text).unwrap(), o);
    // A table that gives the default mode is not the table that leaves it out.
    assert_ne!(o, toml::from_str("opacity = 0.6").unwrap());
    // Options built in code write what differs from the defaults.
    let built = CompositeOptions {
        opacity: 0.6,
        stages: vec![(1.0, 3.0)],
        ..Default::default()
    };
    assert_eq!(
        toml::to_string(&built).unwrap(),
        "opacity = 0.6\nstages = [[1.0, 3.0]]\n"
    );
    assert_eq!(toml::to_string(&CompositeOptions::default()).unwrap(), "");
    let every = toml::to_string(&CompositeOptions::default().with_every_key()).unwrap();
    // TOML has no null: `edge_color`, `axes_frame`, `title`, `cutaway` and `cubes`, None by
    // default, are left out.
    assert_eq!(every.lines().count(), CompositeOptions::KEYS.len() - 5);
    // (The keys left out are not given when read back.)
    assert_eq!(
        toml::from_str::<CompositeOptions>(&every)
            .unwrap()
            .with_every_key(),
        CompositeOptions::default().with_every_key()
    );
}

#[test]
fn unknown_duplicate_and_mistyped_keys_are_errors() {
    let e = toml::from_str::<CompositeOptions>("opacty = 1").unwrap_err();
    assert!(e
        .message()
        .starts_with("unknown field `opacty`, expected one of `mode`"));
    let e = toml::from_str::<CompositeOptions>("mode = \"mpi\"").unwrap_err();
    assert!(e.message().contains("unknown variant `mpi`"), "{e}");
    assert!(toml::from_str::<CompositeOptions>("size = [1]").is_err());
    assert!(toml::from_str::<CompositeOptions>("axis = -1").is_err());
    assert!(toml::from_str::<CompositeOptions>("labels = 1").is_err());
    // Duplicate keys (TOML refuses them itself; a map that has them is refused here).
    use serde::de::value::{Error, MapDeserializer};
    let pairs = [("opacity", 0.5), ("opacity", 0.7)];
    let de = MapDeserializer::<_, Error>::new(pairs.into_iter());
    let e = CompositeOptions::deserialize(de).unwrap_err();
    assert_eq!(e.to_string(), "duplicate field `opacity`");
}

#[test]
fn validate_needs_no_retina_and_validate_for_checks_against_one() {
    let ok = CompositeOptions::default();
    assert_eq!(ok.validate(), Ok(()));
    let key = |o: CompositeOptions| o.validate().unwrap_err().key;
    assert_eq!(
        key(CompositeOptions {
            strip_height: 0,
            size: (0, 0),
            ..Default::default()
        }),
        "strip_height"
    );
    assert_eq!(
        key(CompositeOptions {
            stages: vec![(1.0, 3.0), (f64::INFINITY, 3.0)],
            ..Default::default()
        }),
        "stages[1]"
    );
    // Fine on their own, wrong for the retina.
    let slices = CompositeOptions {
        mode: CompositeMode::Slices,
        axis: 3,
        depth_cue: 0.5,
        stages: vec![(1.0, 1.05)],
        ..Default::default()
    };
    assert_eq!(slices.validate(), Ok(()));
    let for_shape = |o: &CompositeOptions, shape: &[usize], depth| {
        o.validate_for(shape, depth).map_err(|e| e.key)
    };
    assert_eq!(
        for_shape(&slices, &[4, 4, 4, 4], false).unwrap_err(),
        "depth_cue"
    );
    assert_eq!(for_shape(&slices, &[4, 4, 4, 4], true).unwrap_err(), "axis");
    let stage = CompositeOptions {
        axis: 2,
        ..slices.clone()
    };
    // A 4-axis retina has one stage. A collapsed axis of 4 cells among axes of 4 spans ±1,
    // so the eye at d = 1.05 is outside the box and d = 0.95 inside; an axis of 2 cells
    // spans ±0.5.
    assert_eq!(for_shape(&stage, &[4, 4, 4, 4], true), Ok(()));
    assert_eq!(for_shape(&stage, &[2, 4, 4, 4], true), Ok(()));
    assert_eq!(for_shape(&stage, &[4, 4, 4], true).unwrap_err(), "stages");
    let near = CompositeOptions {
        stages: vec![(1.0, 0.95)],
        ..stage
    };
    assert_eq!(
        for_shape(&near, &[4, 4, 4, 4], true).unwrap_err(),
        "stages[0]"
    );
    assert_eq!(for_shape(&near, &[2, 4, 4, 4], true), Ok(()));
    // N ≤ 3 retinas have no slices axis to check (and no stages).
    let flat = CompositeOptions {
        stages: vec![],
        ..slices
    };
    assert_eq!(for_shape(&flat, &[4, 4], true), Ok(()));
    assert_eq!(for_shape(&flat, &[4, 4, 4], true).unwrap_err(), "axis");
}

const SCENE: &str = r#"dim = 4
[camera]
position = [0, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = [6, 5, 4]

[[objects]]
shape = "simplex"

[composite]
mode = "volume"
opacity = 0.6
"#;

fn scene_err(text: &str) -> String {
    match load_toml_str(text, "scene.toml", None) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("expected an error for:\n{text}"),
    }
}

/// The line and column of the first `needle` in `text`.
fn at(text: &str, needle: &str) -> (usize, usize) {
    let line = text.lines().position(|l| l.contains(needle)).unwrap();
    let col = text.lines().nth(line).unwrap().find(needle).unwrap();
    (line + 1, col + 1)
}

#[test]
fn the_scene_table_round_trips_as_it_was_given() {
    let (desc, _) = load_toml_str(SCENE, "scene.toml", None).unwrap();
    let c = desc.composite.as_ref().unwrap();
    assert_eq!((c.mode, c.opacity), (CompositeMode::Volume, 0.6));
    let text = to_toml(&desc).unwrap();
    assert!(
        text.ends_with("\n[composite]\nmode = \"volume\"\nopacity = 0.6\n"),
        "{text}"
    );
    let (again, _) = load_toml_str(&text, "again.toml", None).unwrap();
    assert_eq!(again, desc);
    assert_eq!(to_toml(&again).unwrap(), text);
}

#[test]
fn a_bad_value_gets_one_message_whichever_way_it_arrives() {
    let rgba = vec![0f32; 4 * 5 * 6 * 4];
    // (the line to replace, its replacement, where the bad value starts in its line)
    let cases: [(&str, &str, &str); 8] = [
        ("opacity = 0.6", "opacity = -1", "-1"),
        ("opacity = 0.6", "size = [0, 10]", "[0, 10]"),
        ("opacity = 0.6", "azimuth = nan", "nan"),
        ("opacity = 0.6", "background = [0, inf, 0]", "inf"),
        ("opacity = 0.6", "distance = 1", "1"),
        ("opacity = 0.6", "step = 5", "5"),
        ("mode = \"volume\"", "mode = \"slices\"\naxis = 3", "3"),
        ("opacity = 0.6", "stages = [[1, 3]]", "[[1, 3]]"),
    ];
    for (from, to, value) in cases {
        let text = SCENE.replace(from, to);
        let desc: crate::scene::SceneDesc = toml::from_str(&text).unwrap();
        let options = desc.composite.unwrap();
        let direct = super::super::composite(&rgba, Some(&rgba[..120]), &[4, 5, 6], &options)
            .unwrap_err()
            .to_string();
        let bad_line = to.lines().last().unwrap();
        let (line, col) = at(&text, bad_line);
        let col = col + bad_line.rfind(value).unwrap();
        assert_eq!(
            scene_err(&text),
            format!("scene.toml:{line}:{col}: composite.{direct}"),
            "{to}"
        );
    }
    // Deserialization errors are located too, with suggestions.
    let text = SCENE.replace("opacity = 0.6", "opacty = 0.6");
    let e = scene_err(&text);
    assert!(
        e.ends_with("composite.opacty: unknown key \"opacty\" (did you mean \"opacity\"?)"),
        "{e}"
    );
    let text = SCENE.replace("\"volume\"", "\"mpi\"");
    let (line, col) = at(&text, "\"mpi\"");
    assert_eq!(
        scene_err(&text),
        format!(
            "scene.toml:{line}:{col}: composite.mode: unknown mode \"mpi\" (expected one of \
                 \"volume\", \"mip\", \"first_hit\", \"slices\", \"illustrative\")"
        )
    );
    // A 5D scene's retina has one stage, whose eye must be outside the box.
    let five = SCENE
        .replace("dim = 4", "dim = 5")
        .replace("[0, 0, 0, 5]", "[0, 0, 0, 0, 5]")
        .replace("[0, 0, 0, 0]", "[0, 0, 0, 0, 0]")
        .replace(
            "[[0, 1, 0, 0], [0, 0, 1, 0]]",
            "[[0, 1, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0]]",
        )
        .replace("resolution = [6, 5, 4]", "resolution = 4");
    assert!(load_toml_str(&five, "five.toml", None).is_ok());
    let e = scene_err(&five.replace("opacity = 0.6", "stages = [[1, 0.5]]"));
    assert!(
        e.contains(": composite.stages[0]: (f, d) = (1, 0.5): need f > 0 and d > 1"),
        "{e}"
    );
}

#[test]
fn legend_and_axes_take_auto_true_or_false() {
    for (text, want) in [
        ("\"auto\"", Toggle::Auto),
        ("true", Toggle::On),
        ("false", Toggle::Off),
    ] {
        let o: CompositeOptions =
            toml::from_str(&format!("legend = {text}\naxes = {text}")).unwrap();
        assert_eq!((o.legend, o.axes), (want, want));
        assert_eq!(
            toml::to_string(&o).unwrap(),
            format!("legend = {text}\naxes = {text}\n")
        );
    }
    let bad = toml::from_str::<CompositeOptions>("legend = \"yes\"")
        .unwrap_err()
        .to_string();
    assert!(
        bad.contains("expected \"auto\", true or false, got \"yes\""),
        "{bad}"
    );
    let bad = toml::from_str::<CompositeOptions>("axes = 1")
        .unwrap_err()
        .to_string();
    assert!(bad.contains("\"auto\", true or false"), "{bad}");
    assert!(Toggle::Auto.resolve(true) && !Toggle::Auto.resolve(false));
    assert!(Toggle::On.resolve(false) && !Toggle::Off.resolve(true));
}

#[test]
fn title_and_axes_frame_are_checked() {
    let long = CompositeOptions {
        title: Some("x".repeat(MAX_TITLE_CHARS + 1)),
        ..Default::default()
    };
    assert_eq!(long.validate().unwrap_err().key, "title");
    let two = CompositeOptions {
        title: Some("a\nb".into()),
        ..Default::default()
    };
    assert_eq!(two.validate().unwrap_err().key, "title");
    let nan = CompositeOptions {
        axes_frame: Some(vec![vec![1.0, f64::NAN], vec![0.0, 1.0]]),
        ..Default::default()
    };
    assert_eq!(nan.validate().unwrap_err().key, "axes_frame[0][1]");
    // N×N for the retina's N.
    let square = CompositeOptions {
        axes_frame: Some(vec![vec![1.0, 0.0], vec![0.0, 1.0]]),
        ..Default::default()
    };
    let e = square.validate_for(&[4, 4, 4], false).unwrap_err();
    assert_eq!(e.key, "axes_frame");
    assert!(
        e.message.contains("expected 4 rows of 4 numbers"),
        "{}",
        e.message
    );
    assert!(square.validate_for(&[4], false).is_ok());
}
