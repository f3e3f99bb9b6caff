//! Golden snapshots (insta) of a small cell and a short path, and checks
//! that every picture and chart is XML with the expected elements.

use crate::DrawError;
use crate::cell::{Mark, Picture, Place, Product, ProductState, UR10_REACH, picture};
use crate::charts::{
    Latencies, ProductTimes, StudyPoint, SuccessRate, execution_times, latencies, study,
    success_rates,
};
use crate::path::{EventKind, Sample, ToolPath};
use packwright_interface::scene::{BoxSpec, CellScene, SlotSpec};
use quick_xml::Reader;
use quick_xml::events::Event;

/// The README's bench cell, with a fourth slot outside its box.
fn bench() -> CellScene {
    let slot = |name: &str, x: f64| SlotSpec {
        name: name.into(),
        position: [x, 0.58],
        box_index: 0,
    };
    CellScene {
        name: "bench".into(),
        base: [0.0, 0.0, 0.0],
        suction: 0.1,
        lift: 0.15,
        speed: 1.0,
        grip_settle: 0.1,
        release_settle: 0.5,
        descent: 1.0,
        pending: ([0.45, -0.50], [0.85, -0.10]),
        boxes: vec![BoxSpec {
            name: "tray".into(),
            centre: [0.0, 0.65],
            size: [0.40, 0.30, 0.08],
        }],
        slots: vec![
            slot("g1", -0.12),
            slot("g2", 0.0),
            slot("g3", 0.12),
            slot("g4", 0.35),
        ],
    }
}

fn product(name: &str, size: [f64; 3], at: [f64; 2], state: ProductState) -> Product {
    Product {
        name: name.into(),
        size,
        centre: [at[0], at[1], size[2] / 2.0],
        state,
    }
}

fn small_picture() -> Picture {
    let mut p = Picture::new("bench: order hamper", bench());
    p.reach = Some(UR10_REACH);
    p.products = vec![
        product("A", [0.05; 3], [0.50, -0.20], ProductState::Waiting),
        product(
            "E",
            [0.06, 0.04, 0.05],
            [0.68, -0.38],
            ProductState::Waiting,
        ),
        product("F", [0.05; 3], [0.12, 0.58], ProductState::WorkerPacked),
        product("G", [0.05; 3], [0.75, -0.20], ProductState::Missing),
    ];
    p.assignment = vec![(0, 2), (1, 0), (2, 2), (3, 1)];
    p.marks = vec![
        Mark {
            place: Place::Slot(3),
            code: "E030".into(),
            message: "slot `g4` is outside box `tray`".into(),
        },
        Mark {
            place: Place::Point([1.0, 1.0, 0.3]),
            code: "E039".into(),
            message: "the robot cannot reach the hover above `A`".into(),
        },
    ];
    p
}

/// A pick and place: down to A, suction on, over to g3, off, up.
fn short_path() -> ToolPath {
    let mut samples = Vec::new();
    let mut go = |from: [f64; 3], to: [f64; 3], suction: bool, steps: usize| {
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            samples.push(Sample {
                tip: [
                    from[0] + (to[0] - from[0]) * t,
                    from[1] + (to[1] - from[1]) * t,
                    from[2] + (to[2] - from[2]) * t,
                ],
                suction,
                // Rest to rest: slow at both ends.
                speed: (std::f64::consts::PI * t).sin(),
            });
        }
    };
    let home = [0.65, -0.30, 0.40];
    let above = [0.50, -0.20, 0.15];
    let top = [0.50, -0.20, 0.05];
    let lift = [0.50, -0.20, 0.20];
    let slot = [0.12, 0.58, 0.25];
    let release = [0.12, 0.58, 0.06];
    go(home, above, false, 20);
    go(above, top, false, 10);
    go(top, lift, true, 10);
    go(lift, slot, true, 30);
    go(slot, release, true, 10);
    go(release, slot, false, 10);
    let mut path = ToolPath::from_samples(&samples, &[above, top, lift, slot, release, slot]);
    path.events.push(crate::path::Event {
        at: lift,
        kind: EventKind::Fallback("placing 1: the policy's 60 steps ended 35 mm away".into()),
    });
    path.events.push(crate::path::Event {
        at: slot,
        kind: EventKind::Failure("placing 3: would collide (cup with box:tray)".into()),
    });
    path
}

/// Elements whose `class` holds `class` (one of its words).
fn count(svg: &str, class: &str) -> usize {
    let mut reader = Reader::from_str(svg);
    let mut n = 0;
    loop {
        match reader.read_event() {
            Ok(Event::Start(e)) | Ok(Event::Empty(e)) => {
                if let Ok(Some(a)) = e.try_get_attribute("class") {
                    let v = String::from_utf8_lossy(&a.value).into_owned();
                    if v.split_whitespace().any(|w| w == class) {
                        n += 1;
                    }
                }
            }
            Ok(Event::Eof) => break,
            Ok(_) => {}
            Err(e) => panic!("not XML at {}: {e}", reader.buffer_position()),
        }
    }
    n
}

/// The text of every `<text>` element, trimmed.
fn texts(svg: &str) -> Vec<String> {
    let mut reader = Reader::from_str(svg);
    let mut out = Vec::new();
    loop {
        match reader.read_event() {
            Ok(Event::Text(t)) => {
                let text = String::from_utf8_lossy(&t).trim().to_owned();
                if !text.is_empty() {
                    out.push(text);
                }
            }
            Ok(Event::Eof) => break,
            Ok(_) => {}
            Err(e) => panic!("not XML at {}: {e}", reader.buffer_position()),
        }
    }
    out
}

#[test]
fn small_cell_snapshot() {
    let svg = picture(&small_picture()).expect("draws");
    insta::assert_snapshot!("small_cell", svg);
}

#[test]
fn small_cell_has_every_product_slot_arrow_and_mark() {
    let svg = picture(&small_picture()).expect("draws");
    assert_eq!(count(&svg, "product"), 4);
    assert_eq!(count(&svg, "product-side"), 4);
    assert_eq!(count(&svg, "slot"), 4);
    assert_eq!(count(&svg, "slot-side"), 4);
    assert_eq!(count(&svg, "box"), 1);
    assert_eq!(count(&svg, "missing"), 1);
    assert_eq!(count(&svg, "worker-packed"), 1);
    // No arrow for the product a worker packed.
    assert_eq!(count(&svg, "assignment"), 3);
    assert_eq!(count(&svg, "diagnostic"), 2);
    assert_eq!(count(&svg, "reach"), 1);
    assert!(svg.contains("id=\"slot-g4\""));
    assert!(svg.contains("E030: slot `g4` is outside box `tray`"));
    // The same input gives the same bytes.
    assert_eq!(svg, picture(&small_picture()).expect("draws"));
}

#[test]
fn the_cell_is_at_true_scale() {
    let svg = picture(&small_picture()).expect("draws");
    // The tray is 0.40 m x 0.30 m: 120 x 90 px at 300 px/m.
    assert!(
        svg.contains("width=\"120.0\" height=\"90.0\" fill=\"#f3e5d0\""),
        "{svg}"
    );
}

#[test]
fn short_path_snapshot() {
    let mut p = Picture::new("bench: a short path", bench());
    p.cell.slots.truncate(3);
    p.products = vec![product(
        "A",
        [0.05; 3],
        [0.50, -0.20],
        ProductState::Waiting,
    )];
    p.path = Some(short_path());
    let svg = picture(&p).expect("draws");
    // Three stages, in both views; four rests after moving; one pick, one
    // release; the fallback and the failure in both views.
    assert_eq!(count(&svg, "approach"), 2);
    assert_eq!(count(&svg, "carry"), 2);
    assert_eq!(count(&svg, "retreat"), 2);
    assert_eq!(count(&svg, "subgoal"), 2 * 6);
    assert_eq!(count(&svg, "pick"), 2);
    assert_eq!(count(&svg, "release"), 2);
    assert_eq!(count(&svg, "fallback"), 2);
    assert_eq!(count(&svg, "failure"), 2);
    insta::assert_snapshot!("short_path", svg);
}

#[test]
fn non_finite_input_is_refused() {
    let mut p = small_picture();
    p.products[0].centre[0] = f64::NAN;
    assert_eq!(
        picture(&p),
        Err(DrawError::NonFinite {
            what: "product `A`".into()
        })
    );
    let mut p = small_picture();
    p.assignment.push((9, 0));
    assert!(matches!(picture(&p), Err(DrawError::BadIndex { .. })));
}

#[test]
fn a_picture_too_large_to_draw_at_true_scale_is_refused_at_once() {
    // A pending area 10^20 m out (a unit lost in a typo) would be a
    // picture of 10^23 pixels with 10^21 grid lines.
    let mut p = small_picture();
    p.cell.pending.0[0] = 1e20;
    assert!(matches!(
        picture(&p),
        Err(DrawError::TooLarge { axis: 'x', .. })
    ));
    let mut p = small_picture();
    p.cell.boxes[0].size[2] = 60.0;
    assert!(matches!(
        picture(&p),
        Err(DrawError::TooLarge { axis: 'z', .. })
    ));
    // A large cell that is still a cell is drawn.
    let mut p = small_picture();
    p.cell.boxes[0].size[2] = 5.0;
    assert!(picture(&p).is_ok());
}

fn rates() -> Vec<SuccessRate> {
    let r = |suite: &str, planner: &str, rate: f64, low: f64, high: f64| SuccessRate {
        suite: suite.into(),
        planner: planner.into(),
        rate,
        low,
        high,
        n: 5,
    };
    vec![
        r("case1", "learned", 1.0, 0.57, 1.0),
        r("case1", "rrt", 0.8, 0.38, 0.96),
        r("case2", "learned", 0.6, 0.23, 0.88),
        r("case2", "expert", 1.0, 0.57, 1.0),
    ]
}

#[test]
fn charts_are_xml_with_their_series() {
    let svg = success_rates(&rates()).expect("draws");
    let t = texts(&svg);
    for name in ["case1", "case2", "learned", "rrt", "expert"] {
        assert!(t.iter().any(|s| s == name), "{name} missing in {t:?}");
    }
    let lat = vec![
        Latencies {
            planner: "learned".into(),
            decision_us: vec![5.0, 6.0, 7.0],
            subgoal_us: vec![20.0, 30.0],
            network_us: vec![40.0, 400.0, 4000.0],
        },
        Latencies {
            planner: "rrt".into(),
            subgoal_us: vec![1000.0, 20000.0],
            ..Latencies::default()
        },
    ];
    let svg = latencies(&lat).expect("draws");
    let t = texts(&svg);
    for name in [
        "learned (3)",
        "rrt (2)",
        "decision",
        "sub-goal",
        "sub-goal + action",
    ] {
        assert!(t.iter().any(|s| s == name), "{name} missing in {t:?}");
    }
    let times = vec![ProductTimes {
        planner: "learned".into(),
        execution_s: vec![3.1, 2.9],
        bound_s: vec![2.0, 2.2],
    }];
    let svg = execution_times(&times).expect("draws");
    assert!(texts(&svg).iter().any(|s| s == "learned (2 products)"));
    assert!(svg.matches("<circle").count() >= 2);
    assert_eq!(svg, execution_times(&times).expect("draws"));
}

#[test]
fn charts_refuse_non_finite_numbers() {
    let mut r = rates();
    r[0].high = f64::INFINITY;
    assert!(matches!(
        success_rates(&r),
        Err(DrawError::NonFinite { .. })
    ));
}

#[test]
fn a_study_has_one_line_per_series_and_a_bar_per_point() {
    let p = |series: &str, x: f64, rate: f64| StudyPoint {
        series: series.into(),
        x,
        rate,
        low: (rate - 0.1).max(0.0),
        high: (rate + 0.05).min(1.0),
        n: 100,
    };
    let points = vec![
        p("m_case1_3of5", 0.5, 0.9),
        p("m_case1_3of5", 0.25, 0.7),
        p("m_case1_3of5", 1.0, 1.0),
        p("m_case2_4of5", 0.25, 0.5),
        p("m_case2_4of5", 1.0, 0.8),
    ];
    let svg = study(&points, "Success against training ratio", "training ratio").expect("draws");
    let t = texts(&svg);
    for name in ["m_case1_3of5", "m_case2_4of5", "training ratio", "0.3"] {
        assert!(t.iter().any(|s| s == name), "{name} missing in {t:?}");
    }
    assert_eq!(svg.matches("<circle").count(), points.len());
    assert!(svg.matches("<polyline").count() >= 2);
    assert_eq!(
        svg,
        study(&points, "Success against training ratio", "training ratio").expect("draws")
    );
    let mut bad = points.clone();
    bad[1].x = f64::NAN;
    assert!(matches!(
        study(&bad, "t", "x"),
        Err(DrawError::NonFinite { .. })
    ));
}
