use super::page::paper_edge_bytes_per_sample;
use super::reading::{differences, reading};
use super::*;

#[test]
fn the_papers_own_counts_give_its_integrated_reduction() {
    let (lo, hi) = paper_integrated_reduction();
    assert_eq!((pct(lo), pct(hi)), ("72.5%".to_string(), "74.1%".to_string()));
}

#[test]
fn the_papers_edge_scratch_is_58_bytes_a_sample_on_every_cubic_row() {
    assert_eq!(format!("{:.0}", paper_edge_bytes_per_sample()), "58");
    for (prefix, _, dims) in OBJECTS {
        let p = PAPER.iter().find(|p| p.id == format!("{prefix}_su")).unwrap();
        let per_sample = p.b_edges as f64 / dims.iter().product::<usize>() as f64;
        assert!((per_sample - 58.0).abs() < 0.1, "{prefix}: {per_sample}");
    }
}

#[test]
fn the_papers_table_gives_its_texts_averages_and_aspect_ranges() {
    // Section 4.1: "an average reduction of 79.53%" and "72.20%".
    assert_eq!(format!("{:.2}", paper_mean_discard('i')), "79.53");
    assert_eq!(format!("{:.2}", paper_mean_discard('p')), "72.20");
    assert_eq!(paper_aspect_range('u'), (5.81, 1207.37));
    assert_eq!(paper_aspect_range('i'), (1.16, 2.16));
    assert_eq!(paper_aspect_range('p'), (1.23, 1.39));
}

#[test]
fn the_reading_follows_the_rows() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../report/data/costen_table.json"))
        .expect("committed data");
    let mut data: Data = serde_json::from_str(&text).expect("costen_table data");
    assert!(reading(&data.rows).starts_with("**Reading.** Integrated clustering discards"));
    let r = differences(&data.rows, "70%", "75%");
    assert!(r.contains("removes 70% of our asteroid's triangles against the paper's 75%"), "{r}");
    let said = |rows: &[Row]| {
        let (tets, tris) = counts::ratios(rows, |id| PAPER.iter().find(|p| p.id == id).copied()).unwrap();
        format!("our tetrahedra are {:.2}x the paper's and our triangles {:.2}x", tets.median, tris.median)
    };
    assert!(r.contains(&said(&data.rows)), "{r}");
    // Ten times the triangles on every row: the ratio in the text follows.
    for row in &mut data.rows {
        row.n_triangles *= 10;
    }
    let turned = differences(&data.rows, "70%", "75%");
    assert!(turned.contains(&said(&data.rows)) && turned != r, "{turned}");
    assert_eq!((reading(&[]), differences(&[], "", "")), (String::new(), String::new()));
}
