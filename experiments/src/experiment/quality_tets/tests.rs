//! The page's reading and the front page's pick follow the numbers.

use super::data::{Data, PeerInput, PeerRow, Peers, Quality, Row};
use super::page::{pick_over, reading};
use super::{PEER_CELLS, SCULPT, STUFFING};

fn quality(min: f64, to_surface: f64, inverted: usize) -> Quality {
    Quality {
        tetrahedra: 1000,
        dihedral: [min, 150.0],
        radius_ratio: [1.1, 3.0],
        inverted,
        to_surface_h: [0.0, to_surface],
        from_surface_h: [0.05, 0.5],
        volume_ratio: 0.99,
        encloses: false,
    }
}

fn row(model: &str, tool: &str, cells: usize, q: Quality) -> Row {
    Row { model: model.into(), tool: tool.into(), cells, h: 0.1, quality: q, sampling_ms: vec![1.0], extraction_ms: vec![4.0] }
}

fn peer(model: &str, tool: &str, q: Option<Quality>) -> PeerRow {
    PeerRow {
        model: model.into(),
        tool: tool.into(),
        error: q.is_none().then(|| "failed".to_owned()),
        quality: q,
        seconds: vec![1.0],
        settings: String::new(),
        target: 1000,
        tries: 1,
    }
}

fn data(stuffing_min: f64) -> Data {
    Data {
        models: vec!["a".into(), "b".into()],
        closed: vec!["a".into()],
        cells: vec![PEER_CELLS],
        peer_cells: PEER_CELLS,
        declared: [9.3, 161.7],
        paper: [10.7, 164.8],
        settings: Vec::new(),
        rows: vec![
            row("a", STUFFING, PEER_CELLS, quality(stuffing_min, 0.0, 0)),
            // Off the open model's surface (its holes' patch): still a mesh of the model.
            row("b", STUFFING, PEER_CELLS, quality(15.0, 2.0, 0)),
            // An enclosure, off the closed model's surface: not a candidate.
            row("a", SCULPT, PEER_CELLS, quality(30.0, 0.6, 0)),
            row("b", SCULPT, PEER_CELLS, quality(30.0, 0.6, 0)),
        ],
        figure: None,
    }
}

fn peers() -> Peers {
    Peers {
        inputs: vec![PeerInput { model: "a".into(), how: "its own".into(), triangles: 10 }],
        match_tolerance: 0.1,
        rows: vec![
            peer("a", "fTetWild", Some(quality(12.0, 0.01, 0))),
            peer("b", "fTetWild", Some(quality(13.0, 0.01, 0))),
            // Inverts a tetrahedron: not a candidate however good its angles.
            peer("a", "Inverter", Some(quality(40.0, 0.0, 1))),
            peer("b", "Inverter", Some(quality(40.0, 0.0, 0))),
            // Fails on b: the comparison narrows to the models every candidate meshed.
            peer("a", "TetGen", Some(quality(11.0, 0.0, 0))),
            peer("b", "TetGen", None),
        ],
    }
}

#[test]
fn the_pick_is_the_best_worst_angle_of_the_surface_meshers_that_invert_nothing() {
    let c = pick_over(&data(14.0), Some(&peers())).expect("a pick");
    assert_eq!(c.pick, STUFFING);
    assert!(c.why.contains("over the 1 models"), "{}", c.why);
    assert!(c.why.contains("14.0°") && c.why.contains("fTetWild 12.0°") && c.why.contains("TetGen 11.0°"), "{}", c.why);
    assert!(c.why.contains(SCULPT) && c.why.contains("Inverter"), "the left out are named: {}", c.why);
    assert!(c.why.contains("declares every angle within 9.3-161.7°"), "{}", c.why);
    assert!(c.why.contains("No mesh from TetGen on b."), "failures are named: {}", c.why);
    // A peer with a higher floor wins; a tie within a tenth of a degree goes to the declared bound.
    let c = pick_over(&data(10.0), Some(&peers())).expect("a pick");
    assert_eq!(c.pick, "fTetWild");
    assert!(!c.why.contains("declares"), "{}", c.why);
    let c = pick_over(&data(11.95), Some(&peers())).expect("a pick");
    assert_eq!(c.pick, STUFFING);
}

#[test]
fn the_reading_says_whether_stuffing_stays_inside_its_interval_and_how_fast_it_is() {
    let r = reading(&data(14.0), Some(&peers()));
    assert!(r.starts_with("**Reading.**"));
    assert!(r.contains("14.0-150.0°, inside its declared interval"), "{r}");
    // 1000 tetrahedra in 5 ms: 200k a second, at the bar.
    assert!(r.contains("200k-200k tetrahedra a second; 2 of 2 models reach"), "{r}");
    let r = reading(&data(8.0), None);
    assert!(r.contains("outside its declared interval"), "{r}");
    assert!(!r.contains("fTetWild"), "no peers without their data: {r}");
}

fn label_row(input: &str, tool: &str, min: f64, inverted: usize, ms: f64) -> super::data::LabelRow {
    super::data::LabelRow {
        input: input.into(),
        shape: vec![8, 8, 8],
        tool: tool.into(),
        tetrahedra: 1000,
        dihedral: [min, 160.0],
        inverted,
        volume_error: [("1".to_owned(), -0.02), ("2".to_owned(), 0.01)].into(),
        ms: vec![ms],
        cell_size: None,
        tries: None,
        cgal: None,
        error: None,
    }
}

fn labels(rows: Vec<super::data::LabelRow>) -> super::data::Labels {
    super::data::Labels {
        commit: "c".into(),
        dirty: false,
        date: "d".into(),
        cpu: "cpu".into(),
        cores: None,
        os: None,
        python: None,
        numpy: None,
        compiler: None,
        isolab: "0".into(),
        rows,
    }
}

#[test]
fn the_label_map_pick_takes_the_highest_floor_among_meshers_of_every_map_without_inversions() {
    use super::label_pick::pick_over;
    const CGAL: &str = "CGAL Mesh_3";
    let ours = |min| [label_row("m", "lattice-cleaving", min, 0, 10.0), label_row("v", "lattice-cleaving", min, 0, 5.0)];
    // CGAL's floor is higher: picked, the sentence naming ours and the time ratios.
    let mut rows = ours(5.0).to_vec();
    rows.extend([label_row("m", CGAL, 8.0, 0, 1000.0), label_row("v", CGAL, 9.0, 0, 100.0)]);
    let c = pick_over(&labels(rows.clone())).unwrap();
    assert_eq!(c.pick, CGAL);
    assert!(c.why.contains("8.0°") && c.why.contains("lattice-cleaving 5.0°") && c.why.contains("2.0%"), "{}", c.why);
    assert!(
        !c.why.contains("declares") && c.why.contains("lattice-cleaving 0.010x on m; lattice-cleaving 0.050x on v"),
        "{}",
        c.why
    );
    // An inverted tetrahedron on one map puts CGAL out.
    rows[3].inverted = 1;
    let c = pick_over(&labels(rows.clone())).unwrap();
    assert_eq!(c.pick, "lattice-cleaving");
    assert!(c.why.contains("declares every angle within") && c.why.contains("inverting a tetrahedron: CGAL Mesh_3"), "{}", c.why);
    // So does a failed map; a tie within a tenth of a degree goes to the declared interval.
    rows[3] = label_row("v", CGAL, 5.05, 0, 100.0);
    rows[2].error = Some("crashed".into());
    assert_eq!(pick_over(&labels(rows.clone())).unwrap().pick, "lattice-cleaving");
    rows[2].error = None;
    rows[2].dihedral[0] = 5.05;
    let c = pick_over(&labels(rows)).unwrap();
    assert_eq!(c.pick, "lattice-cleaving");
    assert!(c.why.contains("CGAL Mesh_3 100x on m; CGAL Mesh_3 20x on v"), "{}", c.why);
    // Nobody fit: no pick.
    assert!(pick_over(&labels(vec![label_row("m", CGAL, 8.0, 2, 1.0)])).is_none());
}
