//! Section 4.2's questionnaire, re-analysed from the paper's raw answers (Appendix D; the
//! questions' pairs from Appendix C). The paper's "preference factor" of a configuration in a
//! comparison group (same lattice, or same clustering) is, over the group's questions, the mean
//! share of answers preferring it (a question it is not in counts zero); Fig. 29 sums each
//! configuration's two factors. The paper states 18 participants, but Appendix D has 19 answer
//! columns: its Figs. 28-29 are reproduced (to their rounding) with the 18th column left out,
//! so this recomputes both figures with the paper's 18 answers and with all 19, beside the
//! paper's printed values.

use crate::report::markdown_table;

/// Appendix C's questions (left and right configuration) with Appendix D's answers, one letter per
/// participant column: `L` prefer left, `R` prefer right, `N` no preference.
#[rustfmt::skip]
const QUESTIONS: [(&str, &str, &str); 27] = [
    ("ss_bu", "ss_bi", "RRRRRRRRRRRRRLRRLRR"),
    ("ss_bu", "ss_bp", "RRRLRRRRRRRRNRRLRRR"),
    ("ss_bp", "ss_bi", "NNRRRNRRNNRRNRRRRRR"),
    ("ss_su", "ss_si", "RRRRRRRRRRRRRRRLRRR"),
    ("ss_su", "ss_sp", "LLLLRLRRLNRLRLRLLLL"),
    ("ss_sp", "ss_si", "RRRRRRRRRRRRRRRRRRR"),
    ("ss_bu", "ss_su", "LLLLLNLLLLLLLLLRLLL"),
    ("ss_bi", "ss_si", "LNNLNLLLLLRRLLLLNLL"),
    ("ss_bp", "ss_sp", "LLLLLLRLLLLLRLLLLLL"),
    ("bs_bu", "bs_bi", "RRRRRRRRRNRRRRRLRRR"),
    ("bs_bu", "bs_bp", "RRRRRLRRRLRLRRRLRRR"),
    ("bs_bp", "bs_bi", "RRNLRLLNNLNLLRLLNRR"),
    ("bs_su", "bs_si", "RRRNRLRRRLRRRRRLRRR"),
    ("bs_su", "bs_sp", "LRRLRRRRRRRLRRRRLRR"),
    ("bs_sp", "bs_si", "RNNRRRRRRRNRNRRRRRR"),
    ("bs_bu", "bs_su", "RNLRLRLLLNLLLNLRLLL"),
    ("bs_bi", "bs_si", "RRRRLRRLRRRRRNRLLRR"),
    ("bs_bp", "bs_sp", "RNRLNLRRRNNLRLLLRLL"),
    ("as_bu", "as_bi", "RRRRRRRRRLLLRRRLRRR"),
    ("as_bu", "as_bp", "RRRRRRRLRLLRRRRLRRR"),
    ("as_bp", "as_bi", "RNNLLLRLNRNLNRRLNLL"),
    ("as_su", "as_si", "RRRRRLRRRLRRRRRLRRR"),
    ("as_su", "as_sp", "RRRRRRRRRLRRRLRLRRR"),
    ("as_sp", "as_si", "RRNRRLRNRRLRLRRRRRR"),
    ("as_bu", "as_su", "LLLNNRRNRLLLLNLRRRL"),
    ("as_bi", "as_si", "RNRRLRRLRRNLLRRRRRR"),
    ("as_bp", "as_sp", "RRRRRNLRRLNLRNLLRRR"),
];

/// The participants the paper states.
const PAPER_PARTICIPANTS: usize = 18;

/// The answer columns of the paper's raw answers and the participants it states.
pub(super) fn columns_and_participants() -> (usize, usize) {
    (QUESTIONS[0].2.len(), PAPER_PARTICIPANTS)
}
/// The answer column the paper's figures leave out (0-based): found by recomputing Fig. 28 with
/// each column left out in turn; only this one reproduces it (see the test).
const DROPPED_COLUMN: usize = 17;

/// Fig. 28 as printed: for lattices `b` then `s`, the factors of clusterings `u`, `i`, `p`; then
/// for clusterings `u`, `i`, `p`, the factors of lattices `s`, `b`.
const PAPER_FIG28: [f64; 12] = [0.105, 0.419, 0.358, 0.154, 0.562, 0.235, 0.185, 0.667, 0.500, 0.370, 0.352, 0.519];
/// Fig. 29 as printed: rows `u`, `i`, `p`; columns body-centred, simple cubic.
const PAPER_FIG29: [[f64; 2]; 3] = [[0.772, 0.339], [0.790, 1.062], [0.877, 0.586]];

const LATTICES: [char; 2] = ['b', 's'];
const CLUSTERINGS: [char; 3] = ['u', 'i', 'p'];

fn lattice(id: &str) -> char {
    id.chars().nth(3).unwrap_or(' ')
}

fn clustering(id: &str) -> char {
    id.chars().nth(4).unwrap_or(' ')
}

/// The preference factor of the configurations `who` picks over the questions `group` picks,
/// with the answer columns `keep` selects.
fn factor(group: impl Fn(&str, &str) -> bool, who: impl Fn(&str) -> bool, keep: &dyn Fn(usize) -> bool) -> f64 {
    let (mut sum, mut questions) = (0.0, 0usize);
    for (left, right, answers) in QUESTIONS {
        if !group(left, right) {
            continue;
        }
        questions += 1;
        let kept: Vec<char> = answers.chars().enumerate().filter(|(k, _)| keep(*k)).map(|(_, c)| c).collect();
        for (side, id) in [('L', left), ('R', right)] {
            if who(id) {
                sum += kept.iter().filter(|&&c| c == side).count() as f64 / kept.len().max(1) as f64;
            }
        }
    }
    sum / questions.max(1) as f64
}

/// Fig. 28 in the paper's order, from the columns `keep` selects.
fn fig28(keep: &dyn Fn(usize) -> bool) -> [f64; 12] {
    let mut out = [0.0; 12];
    let mut k = 0;
    for l in LATTICES {
        for c in CLUSTERINGS {
            out[k] = factor(|a, b| lattice(a) == l && lattice(b) == l, |id| clustering(id) == c, keep);
            k += 1;
        }
    }
    for c in CLUSTERINGS {
        for l in ['s', 'b'] {
            out[k] = factor(|a, b| clustering(a) == c && clustering(b) == c, |id| lattice(id) == l, keep);
            k += 1;
        }
    }
    out
}

/// Fig. 29 from Fig. 28: each configuration's factor in its lattice group plus in its
/// clustering group; rows `u`, `i`, `p`, columns body-centred, simple cubic.
fn fig29(f: &[f64; 12]) -> [[f64; 2]; 3] {
    let mut out = [[0.0; 2]; 3];
    for (ci, row) in out.iter_mut().enumerate() {
        row[0] = f[ci] + f[6 + 2 * ci + 1];
        row[1] = f[3 + ci] + f[6 + 2 * ci];
    }
    out
}

/// The configuration with the largest weight in a Fig. 29 table: (clustering, lattice).
fn favourite(t: &[[f64; 2]; 3]) -> (char, char) {
    let mut best = (0, 0);
    for (c, row) in t.iter().enumerate() {
        for (l, &w) in row.iter().enumerate() {
            if w > t[best.0][best.1] {
                best = (c, l);
            }
        }
    }
    (CLUSTERINGS[best.0], LATTICES[best.1])
}

/// The section: both figures recomputed, beside the paper's.
pub(super) fn questionnaire_section() -> String {
    let columns = QUESTIONS[0].2.len();
    let paper_columns = |k: usize| k != DROPPED_COLUMN;
    let all_columns = |_: usize| true;
    let (f18, f19) = (fig28(&paper_columns), fig28(&all_columns));
    let (w18, w19) = (fig29(&f18), fig29(&f19));
    let worst = f18.iter().zip(PAPER_FIG28).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let mut md = format!(
        "\n### The questionnaire (section 4.2, Figs. 28-29), re-analysed\n\nFrom the paper's raw answers (Appendix D): {} \
         questions, {columns} answer columns, where the paper states {PAPER_PARTICIPANTS} participants. Recomputing Fig. 28 \
         with each column left out in turn, only leaving out column {} reproduces it (largest difference {worst:.4}, the \
         printed rounding); with all {columns} the factors move by up to {:.3}. A factor is the mean share of answers \
         preferring a configuration over its comparison group's questions.\n\n",
        QUESTIONS.len(),
        DROPPED_COLUMN + 1,
        f18.iter().zip(&f19).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max),
    );
    let labels = ["b: u", "b: i", "b: p", "s: u", "s: i", "s: p", "u: s", "u: b", "i: s", "i: b", "p: s", "p: b"];
    let body: Vec<Vec<String>> = (0..12)
        .map(|k| vec![labels[k].into(), format!("{:.3}", PAPER_FIG28[k]), format!("{:.3}", f18[k]), format!("{:.3}", f19[k])])
        .collect();
    md.push_str("**Fig. 28** (group: configuration)\n\n");
    md.push_str(&markdown_table(
        &["", "paper", &format!("recomputed, {} columns", columns - 1), &format!("all {columns} columns")],
        &body,
    ));
    let body: Vec<Vec<String>> = CLUSTERINGS
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let cell = |l: usize| format!("{:.3} / {:.3} / {:.3}", PAPER_FIG29[c][l], w18[c][l], w19[c][l]);
            vec![name.to_string(), cell(0), cell(1)]
        })
        .collect();
    md.push_str(&format!("\n**Fig. 29** (paper / recomputed from {} columns / from all {columns})\n\n", columns - 1));
    md.push_str(&markdown_table(&["clustering", "body-centred", "simple cubic"], &body));
    let (p, a) = (favourite(&w18), favourite(&w19));
    md.push_str(&format!(
        "\nThe favourite configuration is `{}{}` from the paper's columns and `{}{}` from all of them{}; the paper's \
         is `si`.\n",
        p.1,
        p.0,
        a.1,
        a.0,
        if p == a { ", so the extra column does not change the paper's conclusion" } else { ": the extra column changes it" },
    ));
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_leaving_out_the_18th_column_reproduces_fig_28() {
        let error = |drop: Option<usize>| {
            let f = fig28(&|k| Some(k) != drop);
            f.iter().zip(PAPER_FIG28).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
        };
        assert!(error(Some(DROPPED_COLUMN)) < 0.001, "{}", error(Some(DROPPED_COLUMN)));
        for k in (0..19).filter(|&k| k != DROPPED_COLUMN) {
            assert!(error(Some(k)) > 0.005, "column {k} also reproduces it");
        }
        assert!(error(None) > 0.005);
    }

    #[test]
    fn fig_29_sums_the_two_groups_and_names_the_papers_favourite() {
        let w = fig29(&PAPER_FIG28);
        for (row, paper) in w.iter().zip(PAPER_FIG29) {
            for (a, b) in row.iter().zip(paper) {
                assert!((a - b).abs() < 0.0015, "{a} {b}");
            }
        }
        assert_eq!(favourite(&w), ('i', 's'));
    }
}
