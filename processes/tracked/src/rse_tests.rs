use super::*;
use proptest::prelude::*;

fn spec(primitives: &str) -> Spec {
    parse_spec(&format!(
        "[terrain]\nseed = 1\nfield = [3.0, 3.0]\napproach = 1.0\nrun_out = 1.0\n{primitives}"
    ))
    .unwrap()
}

/// Block heights of the field only, by (field x index, y index).
fn field(g: &Grid) -> impl Fn(usize, usize) -> f64 + '_ {
    move |fx, iy| g.at(g.field_start + fx, iy)
}

#[test]
fn the_same_seed_gives_the_same_blocks_and_another_seed_others() {
    let s = spec("[[primitive]]\ntype = \"random\"\nmin = 0.0\nmax = 0.4\n");
    assert_eq!(generate(&s, 7), generate(&s, 7));
    assert_ne!(generate(&s, 7), generate(&s, 8));
}

#[test]
fn without_primitives_everything_is_ground_and_the_strips_are_ground_always() {
    // The check refuses a spec of no primitives; the generator still makes flat ground of it.
    let flat: Spec =
        toml::from_str("[terrain]\nfield = [3.0, 3.0]\napproach = 1.0\nrun_out = 1.0\n").unwrap();
    let g = generate(&flat, 1);
    assert_eq!((g.nx, g.ny, g.field_start, g.field_nx), (50, 30, 10, 30));
    assert!(g.heights.iter().all(|&h| h == GROUND_M));
    let r = generate(
        &spec("[[primitive]]\ntype = \"random\"\nmin = 0.3\nmax = 0.4\n"),
        1,
    );
    for iy in 0..r.ny {
        for ix in (0..10).chain(40..50) {
            assert_eq!(r.at(ix, iy), GROUND_M, "({ix}, {iy})");
        }
    }
}

#[test]
fn random_blocks_are_ladder_steps_within_bounds_and_all_of_them_occur() {
    let g = generate(
        &spec("[[primitive]]\ntype = \"random\"\nmin = 0.0\nmax = 0.2\n"),
        3,
    );
    let f = field(&g);
    let mut seen = std::collections::BTreeSet::new();
    for iy in 0..g.ny {
        for fx in 0..g.field_nx {
            let h = f(fx, iy);
            assert!([0.0, 0.05, 0.1, 0.2].contains(&h), "{h}");
            seen.insert((h * 100.0) as u32);
        }
    }
    assert_eq!(seen.len(), 4, "holes and heights both occur: {seen:?}");
}

#[test]
fn gaussian_blocks_centre_on_the_mean() {
    let g = generate(
        &spec("[[primitive]]\ntype = \"gaussian\"\nmean = 0.2\nstd = 0.05\n"),
        2,
    );
    let f = field(&g);
    let hs: Vec<f64> = (0..g.ny)
        .flat_map(|iy| (0..g.field_nx).map(move |fx| (fx, iy)))
        .map(|(fx, iy)| f(fx, iy))
        .collect();
    assert!(hs.iter().all(|h| STEPS_M.contains(h)));
    let at_mean = hs.iter().filter(|&&h| h == 0.2).count();
    // Within ±0.05 of the mean (the nearest step is 0.2) lie 68 % of the draws.
    assert!(at_mean * 10 > hs.len() * 6, "{at_mean} of {}", hs.len());
}

#[test]
fn a_hard_horizontal_barrier_is_a_vertical_wall_across_the_field() {
    let g = generate(
        &spec(
            "[[primitive]]\ntype = \"horizontal_barrier\"\nat = 1.5\nwidth = 0.4\nheight = 0.2\n",
        ),
        1,
    );
    let f = field(&g);
    for iy in 0..g.ny {
        for fx in 0..g.field_nx {
            // Block centres 1.35 … 1.65 m lie in the core [1.3, 1.7].
            let inside = (13..17).contains(&fx);
            assert_eq!(
                f(fx, iy),
                if inside { 0.2 } else { GROUND_M },
                "({fx}, {iy})"
            );
        }
    }
}

#[test]
fn softness_turns_the_wall_into_a_staircase_down_to_ground() {
    let g = generate(
        &spec(
            "[[primitive]]\ntype = \"horizontal_barrier\"\nat = 1.5\nwidth = 0.2\n\
             height = 0.4\nsoftness = 100\n",
        ),
        1,
    );
    let f = field(&g);
    // Away from the core (blocks 14, 15) the heights fall step by step, never rising.
    let right: Vec<f64> = (15..30).map(|fx| f(fx, 0)).collect();
    assert!(right.windows(2).all(|w| w[1] <= w[0]), "{right:?}");
    assert_eq!(right[0], 0.4);
    assert_eq!(*right.last().unwrap(), GROUND_M);
    let distinct: std::collections::BTreeSet<u32> =
        right.iter().map(|h| (h * 100.0) as u32).collect();
    assert_eq!(distinct.len(), 4, "0.4, 0.3, 0.2 and ground: {right:?}");
    // Symmetric on the other side.
    for k in 0..14 {
        assert_eq!(f(14 - k, 0), f(15 + k, 0));
    }
}

#[test]
fn a_diagonal_barrier_runs_at_its_angle() {
    let g = generate(
        &spec("[[primitive]]\ntype = \"diagonal_barrier\"\nat = 1.5\nwidth = 0.2\nheight = 0.2\n"),
        1,
    );
    let f = field(&g);
    for iy in 0..g.ny {
        let wall: Vec<usize> = (0..g.field_nx).filter(|&fx| f(fx, iy) == 0.2).collect();
        assert!(!wall.is_empty(), "row {iy} crosses the wall");
        // At 45° the wall's x shifts by one block per block of y.
        let mid = (wall[0] + wall[wall.len() - 1]) as f64 / 2.0;
        let expected = 14.5 - (iy as f64 - 14.5);
        assert!((mid - expected).abs() <= 1.0, "row {iy}: {wall:?}");
    }
}

#[test]
fn a_peak_is_highest_at_its_centre_and_falls_outwards() {
    let g = generate(
        &spec(
            "[[primitive]]\ntype = \"peak\"\ncenter = [1.55, 1.55]\nheight = 0.4\nradius = 1.0\n",
        ),
        1,
    );
    let f = field(&g);
    assert_eq!(f(15, 15), 0.4);
    for fx in 15..29 {
        assert!(f(fx + 1, 15) <= f(fx, 15));
    }
    assert_eq!(f(0, 0), GROUND_M);
}

#[test]
fn hills_are_round_staircases_at_seeded_places() {
    let hill = |count: u32| {
        spec(&format!(
            "[[primitive]]\ntype = \"hills\"\ncount = {count}\nheight = 0.3\nsigma = 0.3\n"
        ))
    };
    let one = generate(&hill(1), 4);
    assert_eq!(one, generate(&hill(1), 4));
    assert_ne!(one, generate(&hill(1), 5), "another seed, another place");
    let f = field(&one);
    let (mut top, mut counts) = ((0, 0), [0usize; 3]);
    for iy in 0..one.ny {
        for fx in 0..one.field_nx {
            let h = f(fx, iy);
            let i = [0.1, 0.2, 0.3].iter().position(|s| *s == h);
            counts[i.unwrap_or_else(|| panic!("{h} at ({fx}, {iy})"))] += 1;
            if h > f(top.0, top.1) {
                top = (fx, iy);
            }
        }
    }
    // Both steps occur; the ground still dominates a 3 × 3 m field.
    assert!(
        counts[1] > 0 && counts[2] > 0 && counts[0] > counts[1] + counts[2],
        "{counts:?}"
    );
    // Heights never rise walking away from the top, either way along x.
    let (cx, cy) = top;
    for fx in cx..one.field_nx - 1 {
        assert!(f(fx + 1, cy) <= f(fx, cy));
    }
    for fx in 1..=cx {
        assert!(f(fx - 1, cy) <= f(fx, cy));
    }
    // More hills cover more blocks, and never lower one (by max).
    let three = generate(&hill(3), 4);
    let raised = |g: &Grid| g.heights.iter().filter(|h| **h > GROUND_M).count();
    assert!(raised(&three) > raised(&one));
}

#[test]
fn primitives_combine_by_max_never_by_sum() {
    let wall =
        "[[primitive]]\ntype = \"horizontal_barrier\"\nat = 1.5\nwidth = 0.4\nheight = 0.2\n";
    let peak = "[[primitive]]\ntype = \"peak\"\ncenter = [1.5, 1.5]\nheight = 0.3\nradius = 0.5\n";
    let both = generate(&spec(&format!("{wall}{peak}")), 1);
    let (w, p) = (generate(&spec(wall), 1), generate(&spec(peak), 1));
    for i in 0..both.heights.len() {
        assert_eq!(both.heights[i], w.heights[i].max(p.heights[i]));
    }
    assert!(both.heights.iter().all(|&h| h <= 0.3));
}

#[test]
fn adding_a_primitive_leaves_the_others_random_blocks_as_they_were() {
    let random = "[[primitive]]\ntype = \"random\"\nmin = 0.0\nmax = 0.1\n";
    let wall =
        "[[primitive]]\ntype = \"horizontal_barrier\"\nat = 0.25\nwidth = 0.1\nheight = 0.4\n";
    let alone = generate(&spec(random), 5);
    let more = generate(&spec(&format!("{random}{wall}")), 5);
    let f = field(&more);
    for iy in 0..alone.ny {
        for fx in 3..alone.field_nx {
            assert_eq!(field(&alone)(fx, iy), f(fx, iy));
        }
    }
}

#[test]
fn bad_specs_name_their_key() {
    let bad = |text: &str, needle: &str| {
        let e = parse_spec(text).unwrap_err();
        assert!(e.contains(needle), "{text:?}: {e}");
    };
    let head = "[terrain]\nfield = [3.0, 3.0]\n";
    bad("[terrain]\nfield = [3.05, 3.0]\n", "terrain.field[0]");
    bad("[terrain]\nfield = [-1.0, 3.0]\n", "terrain.field[0]");
    bad("[terrain]\nfield = [3.0, nan]\n", "terrain.field[1]");
    bad(&format!("{head}approach = -0.1\n"), "terrain.approach");
    bad(&format!("{head}friction = -1.0\n"), "terrain.friction");
    bad(&format!("{head}flank = 0.0\n"), "terrain.flank");
    bad(&format!("{head}colour = 1\n"), "unknown field `colour`");
    bad(
        &format!("{head}[[primitive]]\ntype = \"random\"\nmin = 0.0\nmax = 0.25\n"),
        "line 6: key 'primitive[0].max': 0.25 is not a step",
    );
    bad(
        &format!("{head}[[primitive]]\ntype = \"random\"\nmin = 0.2\nmax = 0.1\n"),
        "key 'primitive[0].min': 0.2 is above max",
    );
    bad(
        &format!("{head}[[primitive]]\ntype = \"gaussian\"\nmean = 0.1\nstd = -1.0\n"),
        "primitive[0].std",
    );
    bad(
        &format!(
            "{head}[[primitive]]\ntype = \"horizontal_barrier\"\nat = 1.0\nwidth = 0.2\n\
             height = 0.2\nsoftness = 101\n"
        ),
        "primitive[0].softness",
    );
    bad(
        &format!(
            "{head}[[primitive]]\ntype = \"diagonal_barrier\"\nat = 1.0\nwidth = 0.2\n\
             height = 0.2\nangle_deg = 90\n"
        ),
        "primitive[0].angle_deg",
    );
    bad(
        &format!(
            "{head}[[primitive]]\ntype = \"peak\"\ncenter = [1.0, 1.0]\nheight = 0.2\nradius = 0\n"
        ),
        "primitive[0].radius",
    );
    let hills = |k: &str| format!("{head}[[primitive]]\ntype = \"hills\"\n{k}");
    bad(
        &hills("count = 0\nheight = 0.2\nsigma = 0.3\n"),
        "primitive[0].count",
    );
    bad(
        &hills("count = 2\nheight = 0.1\nsigma = 0.3\n"),
        "line 6: key 'primitive[0].height': 0.1 m must be above the ground",
    );
    bad(
        &hills("count = 2\nheight = 0.2\nsigma = 0.0\n"),
        "primitive[0].sigma",
    );
    bad(
        &format!("{head}[[primitive]]\ntype = \"cliff\"\n"),
        "unknown variant `cliff`",
    );
    bad(
        &format!("{head}[[primitive]]\ntype = \"peak\"\ncenter = [1.0, 1.0]\nheight = 0.2\n"),
        "missing field `radius`",
    );
}

proptest! {
    #[test]
    fn any_valid_spec_gives_ladder_steps_with_ground_strips(
        seed in any::<u64>(),
        min in 0usize..6, span in 0usize..6,
        at in 0.0f64..3.0, width in 0.1f64..1.0, hi in 3usize..6, soft in 0.0f64..=100.0,
        angle in -80.0f64..80.0, hills in 1u32..6, hill_hi in 3usize..6, sigma in 0.1f64..0.75,
    ) {
        let max = (min + span).min(5);
        let text = format!(
            "[[primitive]]\ntype = \"random\"\nmin = {}\nmax = {}\n\
             [[primitive]]\ntype = \"diagonal_barrier\"\nat = {at}\nwidth = {width}\n\
             height = {}\nsoftness = {soft}\nangle_deg = {angle}\n\
             [[primitive]]\ntype = \"hills\"\ncount = {hills}\nheight = {}\nsigma = {sigma}\n",
            STEPS_M[min], STEPS_M[max], STEPS_M[hi], STEPS_M[hill_hi]
        );
        let g = generate(&spec(&text), seed);
        prop_assert!(g.heights.iter().all(|h| STEPS_M.contains(h)));
        prop_assert!((0..g.ny).all(|iy| g.at(0, iy) == GROUND_M && g.at(g.nx - 1, iy) == GROUND_M));
    }
}
