use super::*;

const HEAD: &str = "[terrain]\nseed = 1\nfield = [3.0, 3.0]\n";

/// The error of `HEAD` followed by `primitives`.
fn refused(primitives: &str) -> String {
    parse_spec(&format!("{HEAD}{primitives}")).unwrap_err()
}

fn peak(center: &str, height: f64, radius: f64) -> String {
    format!(
        "[[primitive]]\ntype = \"peak\"\ncenter = {center}\nheight = {height}\nradius = {radius}\n"
    )
}

fn hills(sigma: f64) -> String {
    format!("[[primitive]]\ntype = \"hills\"\ncount = 4\nheight = 0.3\nsigma = {sigma}\n")
}

#[test]
fn every_shipped_spec_passes() {
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/tracked/terrains");
    for kind in ["random", "hills", "horizontal", "diagonal"] {
        let text = std::fs::read_to_string(dir.join(format!("{kind}.toml"))).unwrap();
        assert!(
            parse_spec(&text).is_ok(),
            "{kind}: {:?}",
            parse_spec(&text).err()
        );
    }
}

#[test]
fn a_terrain_peak_outside_the_field_is_refused() {
    let e = refused(&peak("[4.0, 1.0]", 0.3, 0.5));
    assert!(
        e.starts_with("line 6: key 'primitive[0].center[0]': 4 m is outside the field, whose x runs from 0 to 3 m"),
        "{e}"
    );
    let e = refused(&peak("[1.0, -0.5]", 0.3, 0.5));
    assert!(
        e.starts_with("line 6: key 'primitive[0].center[1]': -0.5 m"),
        "{e}"
    );
    // Its edges are on the field.
    assert!(parse_spec(&format!("{HEAD}{}", peak("[0.0, 3.0]", 0.3, 0.5))).is_ok());
}

#[test]
fn a_terrain_peak_below_the_ground_is_refused() {
    for h in [0.0, 0.05, 0.1] {
        let e = refused(&peak("[1.5, 1.5]", h, 0.5));
        assert!(
            e.starts_with(&format!(
                "line 7: key 'primitive[0].height': {h} m must be above the ground, 0.1 m"
            )),
            "{e}"
        );
    }
}

#[test]
fn a_terrain_spec_without_primitives_is_refused() {
    let e = parse_spec(HEAD).unwrap_err();
    assert!(
        e.starts_with(
            "line 3: key 'primitive': none given; a terrain needs at least one [[primitive]]"
        ),
        "{e}"
    );
    let e = parse_spec(&format!("primitive = []\n{HEAD}")).unwrap_err();
    assert!(e.starts_with("line 1: key 'primitive': none given"), "{e}");
}

#[test]
fn terrain_hills_too_wide_for_the_field_are_refused() {
    // A quarter of the 3 m field is 0.75 m: at σ = 0.75 every hill stood at its centre.
    let e = refused(&hills(0.75));
    assert!(
        e.starts_with("line 8: key 'primitive[0].sigma': 0.75 m is too wide for the 3 × 3 m field")
            && e.contains("below a quarter of its shorter side (0.75 m)"),
        "{e}"
    );
    // The shorter side decides.
    let narrow = "[terrain]\nfield = [10.0, 1.0]\n";
    let e = parse_spec(&format!("{narrow}{}", hills(0.3))).unwrap_err();
    assert!(e.contains("(0.25 m)"), "{e}");
    // A block wide at least, so the hill cannot fall between the blocks' centres.
    let e = refused(&hills(0.05));
    assert!(
        e.contains("key 'primitive[0].sigma': must be at least 0.1 m (a block), got 0.05"),
        "{e}"
    );
    assert!(parse_spec(&format!("{HEAD}{}", hills(0.7))).is_ok());
    assert!(parse_spec(&format!("{HEAD}{}", hills(0.1))).is_ok());
}

#[test]
fn barriers_stand_on_the_field_above_the_ground_and_are_a_block_thick() {
    let wall = |at: f64, width: f64, height: f64| {
        format!(
            "[[primitive]]\ntype = \"horizontal_barrier\"\nat = {at}\nwidth = {width}\nheight = {height}\n"
        )
    };
    assert!(parse_spec(&format!("{HEAD}{}", wall(1.5, 0.4, 0.4))).is_ok());
    let e = refused(&wall(3.5, 0.4, 0.4));
    assert!(
        e.starts_with("line 6: key 'primitive[0].at': 3.5 m is outside the field"),
        "{e}"
    );
    let e = refused(&wall(1.5, 0.05, 0.4));
    assert!(
        e.starts_with("line 7: key 'primitive[0].width': must be between 0.1 and 20 m"),
        "{e}"
    );
    let e = refused(&wall(1.5, 0.4, 0.05));
    assert!(
        e.starts_with("line 8: key 'primitive[0].height': 0.05 m must be above the ground"),
        "{e}"
    );
    let diagonal =
        "[[primitive]]\ntype = \"diagonal_barrier\"\nat = 1.5\nwidth = 50.0\nheight = 0.2\n";
    assert!(refused(diagonal).contains("key 'primitive[0].width'"));
}

#[test]
fn the_remaining_numbers_have_their_ranges() {
    let e = parse_spec("[terrain]\nfield = [3.0, 3.0]\nfriction = 1e3\n").unwrap_err();
    assert_eq!(
        e,
        "line 3: key 'terrain.friction': must be between 0 and 100, got 1000"
    );
    let e = parse_spec("[terrain]\nfield = [3.0, 3.0]\nflank = 25.0\n").unwrap_err();
    assert!(
        e.starts_with("line 3: key 'terrain.flank': must be above 0 and at most 20 m"),
        "{e}"
    );
    let gaussian = |mean: f64, std: f64| {
        format!("[[primitive]]\ntype = \"gaussian\"\nmean = {mean}\nstd = {std}\n")
    };
    assert!(refused(&gaussian(0.5, 0.05)).starts_with("line 6: key 'primitive[0].mean'"));
    assert!(refused(&gaussian(0.2, 1.0)).starts_with("line 7: key 'primitive[0].std'"));
    assert!(refused(&peak("[1.0, 1.0]", 0.3, 0.05)).contains("key 'primitive[0].radius'"));
    // The second primitive is named by its index and found on its own line.
    let e = refused(&format!("{}{}", hills(0.3), peak("[9.0, 1.0]", 0.3, 0.5)));
    assert!(
        e.starts_with("line 11: key 'primitive[1].center[0]'"),
        "{e}"
    );
}

#[test]
fn toml_errors_name_their_line_and_key() {
    let e = parse_spec("[terrain]\nfield = [3.0]\n").unwrap_err();
    assert!(e.starts_with("line 2: key 'terrain.field'"), "{e}");
    let e = parse_spec(&format!("{HEAD}[[primitive]]\ntype = \"peak\"\ncenter = [1.0, 1.0]\nheight = \"high\"\nradius = 1.0\n"))
        .unwrap_err();
    // A primitive's keys are read after its `type`: toml places the error at its table.
    assert!(
        e.starts_with("line 4: key 'primitive[0]': invalid type: string \"high\", expected f64"),
        "{e}"
    );
    let e = parse_spec(&format!("{HEAD}colour = 1\n")).unwrap_err();
    assert!(
        e.starts_with("line 4: key 'terrain.colour': unknown field `colour`"),
        "{e}"
    );
    // Not TOML at all: toml's line, no key.
    let e = parse_spec("[terrain\nfield = 1\n").unwrap_err();
    assert!(e.starts_with("line 1: "), "{e}");
}

#[test]
fn key_paths_split_into_keys_and_indices() {
    let text = |p: &str| {
        segments(p)
            .iter()
            .map(|s| match s {
                Seg::Key(k) => format!("k{k}"),
                Seg::Index(i) => format!("i{i}"),
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    assert_eq!(text("primitive[1].center[0]"), "kprimitive i1 kcenter i0");
    assert_eq!(text("terrain.flank"), "kterrain kflank");
}
