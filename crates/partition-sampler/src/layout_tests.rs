//! Invariants of the compact tree layout over random trees and domains: every stored leaf
//! rectangle contains its cell ∩ domain, lies inside its cell (so no two overlap), and
//! validation rejects every malformed field of a decoded tree.

use proptest::prelude::*;

use crate::error::PersistError;
use crate::leaf::Leaf;
use crate::rect::{Domain, Rect};
use crate::tree::{EMPTY, LEAF, LeafChoice, QuadTree, Scheme, cell_rect};
use crate::{QuadTreeBuilder, TabulatedDensity, UserBoundDensity};

/// `(leaf index, depth, ix, iy)` of every sampleable leaf, sorted by leaf index.
fn leaf_cells(t: &QuadTree) -> Vec<(usize, u32, u64, u64)> {
    let mut out = Vec::new();
    let mut stack = vec![(t.root_code, 0u32, 0u64, 0u64)];
    while let Some((code, d, ix, iy)) = stack.pop() {
        if code == EMPTY {
            continue;
        }
        if code & LEAF != 0 {
            out.push(((code & !LEAF) as usize, d, ix, iy));
            continue;
        }
        let node = t.nodes[code as usize];
        for k in 0..4u64 {
            stack.push((
                node.children[k as usize],
                d + 1,
                2 * ix + (k & 1),
                2 * iy + (k >> 1),
            ));
        }
    }
    out.sort_unstable();
    out
}

/// `a ⊇ b` (closed rectangles).
fn covers(a: &Rect, b: &Rect) -> bool {
    a.x0 <= b.x0 && a.y0 <= b.y0 && a.x1 >= b.x1 && a.y1 >= b.y1
}

/// The layout invariants of one tree; `probe` are points in the root, in `[0, 1]²` units.
fn check_layout(t: &QuadTree, probe: &[[f64; 2]]) -> Result<(), TestCaseError> {
    prop_assert!(t.validate().is_ok());
    let frame = t.frame();
    let cells = leaf_cells(t);
    prop_assert_eq!(
        cells.len(),
        t.leaves.len(),
        "every leaf is reached exactly once"
    );
    let rects: Vec<Rect> = t.leaves.iter().map(|l| l.rect(&frame)).collect();
    for (k, &(i, d, ix, iy)) in cells.iter().enumerate() {
        prop_assert_eq!(i, k);
        let cell = cell_rect(&t.root, d, ix, iy);
        // The f64 bounding box of cell ∩ domain (widened outward for the disc).
        let need = t.domain().rejection_rect(&cell);
        prop_assert!(need.is_some(), "leaf {} has an empty cell", i);
        let need = need.unwrap_or(cell);
        prop_assert!(
            covers(&rects[i], &need),
            "leaf {i}: {:?} ⊉ {:?}",
            rects[i],
            need
        );
        prop_assert!(
            covers(&cell, &rects[i]),
            "leaf {i}: {:?} ⊄ {:?}",
            rects[i],
            cell
        );
        // In stored coordinates: inside the cell's exact edges, upper edges exact in f32.
        let l = &t.leaves[i];
        let s = l.stored_rect();
        let ex = frame.cell_edges(t.root.x0, t.root.width(), d, ix);
        let ey = frame.cell_edges(t.root.y0, t.root.height(), d, iy);
        prop_assert!(s.x0 >= ex[0] && s.x1 <= ex[1] && s.y0 >= ey[0] && s.y1 <= ey[1]);
        prop_assert_eq!(f64::from(l.u0 + l.du), s.x1);
        prop_assert_eq!(f64::from(l.v0 + l.dv), s.y1);
    }
    // No two rectangles overlap in a set of positive area (in the sampler's coordinates):
    // sweep in order of x0, comparing each with the later ones that start before it ends.
    let mut order: Vec<usize> = (0..rects.len()).collect();
    order.sort_by(|&a, &b| rects[a].x0.total_cmp(&rects[b].x0));
    for (k, &a) in order.iter().enumerate() {
        for &b in order[k + 1..]
            .iter()
            .take_while(|&&b| rects[b].x0 < rects[a].x1)
        {
            prop_assert!(
                rects[a].intersect(&rects[b]).is_none(),
                "leaves {a} and {b} overlap: {:?} {:?}",
                rects[a],
                rects[b]
            );
        }
    }
    // Points of the domain whose cell is a sampleable leaf lie in that leaf's rectangle.
    let r = t.root;
    for p in probe {
        let x = [r.x0 + p[0] * r.width(), r.y0 + p[1] * r.height()];
        if let (true, Some(i)) = (t.domain().contains(x), t.locate(x)) {
            prop_assert!(
                rects[i].contains(x),
                "{:?} not in leaf {}: {:?}",
                x,
                i,
                rects[i]
            );
        }
    }
    Ok(())
}

/// `floor + exp(−|x − c|² / (2σ²))` with its exact supremum on a rectangle as the bound:
/// peaked enough to drive trees to depth 24.
fn peak(
    c: [f64; 2],
    sigma: f64,
    floor: f64,
    domain: Domain,
) -> UserBoundDensity<impl Fn([f64; 2]) -> f64 + Sync, impl Fn(&Rect) -> f64 + Sync> {
    let g = move |dx: f64, dy: f64| floor + (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp();
    let f = move |p: [f64; 2]| g(p[0] - c[0], p[1] - c[1]);
    let bound = move |r: &Rect| g(c[0] - c[0].clamp(r.x0, r.x1), c[1] - c[1].clamp(r.y0, r.y1));
    UserBoundDensity::new(f, bound, domain, 2).unwrap()
}

fn schemes() -> impl Strategy<Value = (Scheme, LeafChoice)> {
    proptest::sample::select(crate::SAMPLING_CONFIGS.to_vec())
}

/// Random domains: the disc, rectangles with dyadic roots (identity frame) and arbitrary
/// rectangles (normalised frame).
fn domains() -> impl Strategy<Value = Domain> {
    prop_oneof![
        2 => Just(Domain::UnitDisc),
        1 => Just(Domain::Rect(Rect::UNIT)),
        1 => Just(Domain::Rect(Rect::new(-2.0, 0.0, 2.0, 0.5))),
        2 => (-5.0f64..5.0, -5.0f64..5.0, 0.01f64..4.0, 0.01f64..4.0)
            .prop_map(|(x, y, w, h)| Domain::Rect(Rect::new(x, y, x + w, y + h))),
    ]
}

fn probe() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec(prop::array::uniform2(0.0f64..1.0), 200)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Deep trees around a narrow peak (up to depth 24), any domain and scheme.
    #[test]
    fn stored_rects_cover_cells_and_never_overlap(
        domain in domains(), c in prop::array::uniform2(0.0f64..1.0), log_sigma in -7.0f64..-1.0,
        log_floor in -4.0f64..-0.5, depth in 0u32..=24, n_max in 1.3f64..4.0, tol in prop_oneof![Just(1e-6), Just(1e-12)], (sc, lc) in schemes(),
        pts in probe(),
    ) {
        let r = domain.bounding_rect();
        let mut c = [r.x0 + c[0] * r.width(), r.y0 + c[1] * r.height()];
        if domain == Domain::UnitDisc {
            let n = (c[0] * c[0] + c[1] * c[1]).sqrt().max(1.0);
            c = [c[0] / n, c[1] / n];
        }
        let d = peak(c, 10f64.powf(log_sigma) * r.width(), 10f64.powf(log_floor), domain);
        let t = QuadTreeBuilder::new().n_max(n_max).max_depth(depth).volume_tolerance(tol)
            .scheme(sc).leaf_choice(lc).build_tree(&d);
        let t = t.unwrap();
        check_layout(&t, &pts)?;
    }

    /// Tabulated grids on any rectangle.
    #[test]
    fn tabulated_rects_cover_cells_and_never_overlap(
        (w, h, vals) in (1usize..17, 1usize..17).prop_flat_map(|(w, h)| (Just(w), Just(h),
            prop::collection::vec(prop_oneof![Just(0.0), 0.0f64..10.0, Just(1e5)], w * h))),
        domain in domains().prop_filter("rectangle", |d| *d != Domain::UnitDisc),
        (sc, lc) in schemes(), pts in probe(),
    ) {
        prop_assume!(vals.iter().any(|&v| v > 0.0));
        let d = TabulatedDensity::new(w, h, vals, domain.bounding_rect()).unwrap();
        let t = QuadTreeBuilder::new().scheme(sc).leaf_choice(lc).build_tree(&d).unwrap();
        check_layout(&t, &pts)?;
    }
}

#[test]
fn deepest_trees_reach_the_depth_limit() {
    // The proptest above must exercise depth 24 (the f32-exactness limit).
    let d = peak([0.3, 0.4], 1e-8, 1e-3, Domain::UnitDisc);
    let t = QuadTreeBuilder::new()
        .max_depth(24)
        .volume_tolerance(1e-12)
        .build_tree(&d)
        .unwrap();
    assert_eq!(t.counts.depth, 24);
    let pts: Vec<[f64; 2]> = (0..400)
        .map(|k| [0.65 + 1e-7 * (k % 20) as f64, 0.7 + 1e-7 * (k / 20) as f64])
        .collect();
    check_layout(&t, &pts).unwrap();
}

#[test]
fn round_to_nearest_would_break_coverage() {
    // The check above can fail: encoding the disc bounding boxes with round-to-nearest f32
    // edges (instead of outward) leaves part of some cell ∩ disc outside its rectangle.
    let d = peak([0.0, 0.0], 0.3, 0.1, Domain::UnitDisc);
    let t = QuadTreeBuilder::new().build_tree(&d).unwrap();
    let frame = t.frame();
    assert!(frame.is_identity());
    let mut uncovered = 0;
    for &(i, dd, ix, iy) in &leaf_cells(&t) {
        let need = Domain::UnitDisc
            .rejection_rect(&cell_rect(&t.root, dd, ix, iy))
            .unwrap();
        let l = t.leaves[i];
        let n = |x: f64| x as f32;
        let naive = Leaf {
            u0: n(need.x0),
            v0: n(need.y0),
            du: n(need.x1) - n(need.x0),
            dv: n(need.y1) - n(need.y0),
            ..l
        };
        assert!(covers(&l.rect(&frame), &need));
        uncovered += usize::from(!covers(&naive.rect(&frame), &need));
    }
    assert!(uncovered > 0);
}

/// A small disc tree built with the descent (so every field, the CDFs included, is present).
fn small_tree(choice: LeafChoice) -> QuadTree {
    let d = peak([0.2, -0.3], 0.05, 0.01, Domain::UnitDisc);
    QuadTreeBuilder::new()
        .leaf_choice(choice)
        .build_tree(&d)
        .unwrap()
}

#[test]
fn validation_rejects_malformed_compact_fields() {
    type Mutation = fn(&mut QuadTree);
    let cases: [(&str, LeafChoice, Mutation); 20] = [
        ("du = 0", LeafChoice::Alias, |t| t.leaves[0].du = 0.0),
        ("du < 0", LeafChoice::Alias, |t| t.leaves[0].du = -0.1),
        ("du NaN", LeafChoice::Alias, |t| t.leaves[0].du = f32::NAN),
        ("dv inf", LeafChoice::Alias, |t| {
            t.leaves[0].dv = f32::INFINITY
        }),
        ("u0 NaN", LeafChoice::Alias, |t| t.leaves[0].u0 = f32::NAN),
        ("u0 left of root", LeafChoice::Alias, |t| {
            t.leaves[0].u0 = -2.0
        }),
        ("v0 + dv above root", LeafChoice::Alias, |t| {
            t.leaves[0].v0 = 1.0
        }),
        ("m = 0", LeafChoice::Alias, |t| t.leaves[0].m = 0.0),
        ("m < 0", LeafChoice::Alias, |t| t.leaves[0].m = -1.0),
        ("m NaN", LeafChoice::Alias, |t| t.leaves[0].m = f32::NAN),
        ("m inf", LeafChoice::Alias, |t| {
            t.leaves[0].m = f32::INFINITY
        }),
        ("bound scale 0", LeafChoice::Alias, |t| t.bound_scale = 0.0),
        ("bound scale NaN", LeafChoice::Alias, |t| {
            t.bound_scale = f64::NAN
        }),
        ("m · scale overflows", LeafChoice::Alias, |t| {
            t.leaves[0].m = 4.0;
            t.bound_scale = f64::MAX;
        }),
        ("alias out of range", LeafChoice::Alias, |t| {
            t.leaves[0].alias = u32::MAX
        }),
        ("cdf for alias", LeafChoice::Alias, |t| {
            t.cdf = vec![[0.5; 3]; t.nodes.len()]
        }),
        ("cdf missing", LeafChoice::Descent, |t| t.cdf.clear()),
        ("cdf short", LeafChoice::Descent, |t| {
            t.cdf.pop();
        }),
        ("cdf NaN", LeafChoice::Descent, |t| t.cdf[0][1] = f64::NAN),
        ("cdf > 2", LeafChoice::Descent, |t| t.cdf[0][0] = 3.0),
    ];
    for (name, choice, mutate) in cases {
        let good = small_tree(choice);
        assert!(good.validate().is_ok(), "{name}");
        assert!(good.nodes.len() > 1 && good.leaves.len() > 1);
        let mut bad = good.clone();
        mutate(&mut bad);
        assert!(bad.validate().is_err(), "{name} accepted");
        assert!(
            matches!(
                QuadTree::from_bytes(&bad.to_bytes()),
                Err(PersistError::Corrupt(_))
            ),
            "{name} decoded"
        );
        assert_eq!(QuadTree::from_bytes(&good.to_bytes()).as_ref(), Ok(&good));
    }
}

#[test]
fn sizes_and_byte_counts() {
    assert_eq!(std::mem::size_of::<crate::tree::Node>(), 16);
    let a = small_tree(LeafChoice::Alias);
    assert!(a.cdf.is_empty());
    assert_eq!(a.leaf_bytes(), 40 * a.leaves.len());
    assert_eq!(a.node_bytes(), 16 * a.nodes.len());
    let d = small_tree(LeafChoice::Descent);
    assert_eq!(d.node_bytes(), 40 * d.nodes.len());
    assert_eq!(
        d.bytes_used() - a.bytes_used(),
        24 * a.nodes.len(),
        "only the CDFs differ"
    );
    // A non-dyadic root stores normalised coordinates.
    let r = Rect::new(0.1, 0.2, 0.7, 0.5);
    let t = QuadTreeBuilder::new()
        .build_tree(&peak([0.3, 0.3], 0.05, 0.01, Domain::Rect(r)))
        .unwrap();
    assert!(!t.frame().is_identity());
    assert!(t.leaves.iter().all(|l| l.u0 >= 0.0 && l.u0 + l.du <= 1.0));
}
