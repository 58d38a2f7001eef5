use super::*;

const GOOD: &str = r#"
[solver]
dt = 0.01
substeps = 4
iterations = 2

[effects]
gravity = [0.0, -9.81, 0.0]
drag = 0.01
[effects.wind]
velocity = [3.0, 0.0, 1.0]
gust = 0.2

[[cloth]]
rows = 10
cols = 12
spacing = 0.05
origin = [0.0, 1.0, 0.0]
fabric = "wool"
damping = 0.3
pins = ["first-row-corners", { row = 0 }, { cells = [[1, 1]] }, { region = { min = [0.0, 0.9, -1.0], max = [1.0, 1.1, 1.0] } }]
tethers = 0.05

[output]
steps = 10
frames = 2
"#;

#[test]
fn parses_and_builds() {
    let s = Scene::parse(GOOD, "good.toml").unwrap();
    assert_eq!(s.solver.substeps.0, 4);
    let w = s.world().unwrap();
    assert_eq!(w.particle_count(), 120);
    assert_eq!(w.effects().named(), vec!["gravity", "wind", "drag"]);
    let d = s.cloth[0].get_ref().desc().unwrap();
    assert_eq!(d.fabric.damping, 0.3);
    assert_eq!(d.fabric.mass, crate::Fabric::preset("wool").unwrap().mass);
}

#[test]
fn round_trips_through_toml() {
    let s = Scene::parse(GOOD, "good.toml").unwrap();
    let text = s.to_toml().unwrap();
    let back = Scene::parse(&text, "back.toml").unwrap();
    assert_eq!(back.to_toml().unwrap(), text);
    assert_eq!(back.solver, s.solver);
    assert_eq!(back.effects, s.effects);
    assert_eq!(back.output, s.output);
    assert_eq!(back.cloth.len(), 1);
    assert_eq!(back.cloth[0].get_ref(), s.cloth[0].get_ref());
}

#[test]
fn empty_scene_uses_defaults() {
    let s = Scene::parse("", "empty.toml").unwrap();
    assert_eq!(s.output.steps.0, 300);
    assert_eq!(s.world().unwrap().particle_count(), 0);
}

fn err(text: &str) -> String {
    Scene::parse(text, "bad.toml").unwrap_err().to_string()
}

#[test]
fn bad_scenes_name_key_line_and_column() {
    let cases: &[(&str, &[&str])] = &[
        (
            "[solver]\ndt = -0.1\n",
            &["bad.toml at line 2, column 6", "-0.1", "greater than zero"],
        ),
        ("[solver]\nsubsteps = 0\n", &["line 2, column 12", "at least 1"]),
        ("[solver]\ndtt = 0.1\n", &["line 2, column 1", "unknown field `dtt`"]),
        ("[solver]\ndt = \"fast\"\n", &["line 2, column 6", "invalid type"]),
        ("[effects]\ngravity = [0.0, 1.0]\n", &["line 2, column 11"]),
        ("[effects]\ndrag = -1.0\n", &["line 2, column 8", "zero or greater"]),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.0\n",
            &["line 4, column 11", "greater than zero"],
        ),
        ("[[cloth]]\nrows = 3\ncols = 3\n", &["missing field `spacing`"]),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.1\nfabric = \"silk\"\n",
            &["line 1, column 1", "cloth 0", "silk", "cotton"],
        ),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.1\npins = [{ row = 7 }]\n",
            &["line 1, column 1", "row 7", "3 x 3"],
        ),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.1\npins = [\"everything\"]\n",
            &["line 5", "unknown variant `everything`"],
        ),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.1\nu = [0.0, 0.0, 0.0]\n",
            &["cloth 0", "`u`", "non-zero"],
        ),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.1\nmass = nan\n",
            &["line 5, column 8", "finite"],
        ),
        ("[output]\nsteps = 10\nfps = 3\n", &["line 3, column 1", "unknown field `fps`"]),
        ("this is not toml", &["line 1"]),
        (
            "[[cloth]]\nrows = 3\ncols = 3\nspacing = 0.1\n\n[[cloth]]\nrows = 2\ncols = 2\nspacing = 0.1\nfabric = \"x\"\n",
            &["line 6, column 1", "cloth 1"],
        ),
    ];
    for (text, wants) in cases {
        let e = err(text);
        for w in *wants {
            assert!(e.contains(w), "error for {text:?} lacks {w:?}: {e}");
        }
    }
}

#[test]
fn line_col_counts_from_one() {
    assert_eq!(line_col("ab\ncd", 0), (1, 1));
    assert_eq!(line_col("ab\ncd", 3), (2, 1));
    assert_eq!(line_col("ab\ncd", 4), (2, 2));
}
