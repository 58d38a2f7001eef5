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

const OBSTACLES: &str = r#"
[effects]
gravity = [0.0, -9.81, 0.0]
friction = 0.3

[[cloth]]
rows = 4
cols = 4
spacing = 0.05

[[obstacle]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]

[[obstacle]]
kind = "sphere"
center = [0.0, 0.5, 0.0]
radius = 0.2
velocity = [0.0, 0.0, 0.1]
friction = 0.5

[[obstacle]]
kind = "capsule"
a = [-0.5, 0.3, 0.0]
b = [0.5, 0.3, 0.0]
radius = 0.05

[[obstacle]]
kind = "box"
center = [0.0, 0.1, 0.0]
half_extents = [0.2, 0.1, 0.2]
rotation = [0.0, 45.0, 0.0]

[[obstacle]]
kind = "mesh"
dress_form = 400
offset = [1.0, 0.0, 0.0]
scale = 0.5
broadphase = "grid"
cells = [3, 4, 3]
face_memory = true

[[obstacle]]
kind = "mesh"
dress_form = 400
broadphase = "bvh"
"#;

#[test]
fn obstacles_parse_and_build() {
    let s = Scene::parse(OBSTACLES, "obs.toml").unwrap();
    let w = s.world().unwrap();
    assert_eq!(w.obstacles().len(), 6);
    assert_eq!(w.friction(), 0.3);
    assert_eq!(w.obstacles()[1].friction(), Some(0.5));
    assert!(
        w.obstacles()[4].describe().contains("grid 3x4x3"),
        "{}",
        w.obstacles()[4].describe()
    );
    assert!(w.obstacles()[4].describe().contains("face memory"));
    assert!(
        w.obstacles()[5].describe().to_lowercase().contains("bvh"),
        "{}",
        w.obstacles()[5].describe()
    );
}

fn obstacle_error(table: &str) -> String {
    let text = format!("[[cloth]]\nrows = 2\ncols = 2\nspacing = 0.1\n\n[[obstacle]]\n{table}");
    Scene::parse(&text, "bad.toml").unwrap_err().to_string()
}

#[test]
fn obstacle_errors_carry_line_and_column() {
    let e = obstacle_error("kind = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\n");
    assert!(e.contains("line 9, column 10") && e.contains("out of range"), "{e}");
    let e = obstacle_error("kind = \"sphere\"\ncentre = [0.0, 0.0, 0.0]\nradius = 1.0\n");
    assert!(e.contains("line 8, column 1") && e.contains("centre"), "{e}");
    let e = obstacle_error("kind = \"cone\"\n");
    assert!(e.contains("line 7, column 8") && e.contains("cone"), "{e}");
    let e = obstacle_error("kind = \"mesh\"\ndress_form = 400\nbroadphase = \"octree\"\n");
    assert!(e.contains("line 9") && e.contains("octree"), "{e}");
    let e = obstacle_error("kind = \"box\"\ncenter = [0.0, 0.0, 0.0]\nhalf_extents = [1.0, 0.0, 1.0]\n");
    assert!(e.contains("line 9") && e.contains("out of range"), "{e}");
    // cross-field problems name the obstacle's table
    let e = obstacle_error("kind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nradius = 1.0\nnormal = [0.0, 1.0, 0.0]\n");
    assert!(
        e.contains("line 6, column 1") && e.contains("obstacle 0") && e.contains("`radius` does not apply"),
        "{e}"
    );
    let e = obstacle_error("kind = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\n");
    assert!(e.contains("line 6") && e.contains("needs `radius`"), "{e}");
    let e = obstacle_error("kind = \"mesh\"\n");
    assert!(e.contains("exactly one of `obj` and `dress_form`"), "{e}");
    let e = obstacle_error("kind = \"mesh\"\ndress_form = 400\nbroadphase = \"bvh\"\ncells = [2, 2, 2]\n");
    assert!(e.contains("grid broadphase only"), "{e}");
    let e = obstacle_error("kind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]\n");
    assert!(e.contains("plane.normal"), "{e}");
    let e = obstacle_error("kind = \"mesh\"\nobj = \"/nonexistent/x.obj\"\n");
    assert!(e.contains("line 6"), "{e}");
    let text = "[effects]\nfriction = -0.5\n";
    let e = Scene::parse(text, "f.toml").unwrap_err().to_string();
    assert!(e.contains("line 2, column 12"), "{e}");
}
