//! The page `report/python_users.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::targets;
use super::{HUGE_PAGES, HUGE_PAGES_TUNABLE, LARGE, NAME, OURS, PEERS, THREADS};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{markdown_table, ms, Spread};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data))
}

pub(super) fn spread(row: &Row) -> Spread {
    Spread::of(row.ms.clone())
}

pub(super) fn find<'a>(
    data: &'a Data,
    environment: &str,
    implementation: &str,
    input: &str,
    n: usize,
    threads: usize,
) -> Option<&'a Row> {
    data.rows.iter().find(|r| {
        r.environment == environment && r.implementation == implementation && r.input == input && r.n == n && r.threads == threads
    })
}

/// The inputs in the order run: (input, n).
pub(super) fn inputs(data: &Data) -> Vec<(String, usize)> {
    crate::report::first_seen(data.rows.iter().map(|r| (r.input.clone(), r.n)))
}

pub(super) fn label(input: &str, n: usize, data: &Data) -> String {
    match data.inputs.iter().find(|i| i.input == input && i.n == n) {
        Some(i) if i.shape.len() == 3 && i.shape.iter().all(|&s| s == n) => format!("{input} {n}³"),
        Some(i) => format!("{input} {}", i.shape.iter().map(usize::to_string).collect::<Vec<_>>().join("×")),
        None => format!("{input} {n}"),
    }
}

pub(super) fn ratio(a: f64, b: Option<f64>) -> String {
    match b {
        Some(b) if b > 0.0 => format!("{:.2}", a / b),
        _ => "–".into(),
    }
}

/// One table: per input, every implementation run on `threads` in `environment`, its median and
/// spread and its ratio to ours on the same input, threads and environment (and, for the huge
/// pages run, to its own default run).
pub(super) fn timing_table(data: &Data, environment: &str, threads: usize) -> String {
    let against_default = environment != "default";
    let mut rows = Vec::new();
    for (input, n) in inputs(data) {
        let ours = find(data, environment, OURS, &input, n, threads).map(|r| spread(r).median);
        for r in data.rows.iter().filter(|r| r.environment == environment && r.input == input && r.n == n && r.threads == threads)
        {
            let s = spread(r);
            let mut row = vec![
                label(&input, n, data),
                r.implementation.clone(),
                r.triangles.to_string(),
                ms(s.median),
                format!("{}–{}{}", ms(s.min), ms(s.max), if r.wide == Some(true) { " (wide)" } else { "" }),
                ratio(s.median, ours),
            ];
            if against_default {
                let default = find(data, "default", &r.implementation, &input, n, threads).map(|d| spread(d).median);
                row.push(ratio(s.median, default));
            }
            rows.push(row);
        }
    }
    let ours_header = format!("÷ {OURS}");
    let mut header = vec!["input", "implementation", "triangles", "ms (median)", "fastest–slowest", &ours_header];
    if against_default {
        header.push("÷ its default run");
    }
    markdown_table(&header, &rows)
}

/// The sentence for one input: how many times longer each peer takes than ours, one thread.
pub(super) fn headline(data: &Data, input: &str, n: usize) -> Option<String> {
    let ours = spread(find(data, "default", OURS, input, n, 1)?).median;
    let peers: Vec<String> = PEERS
        .iter()
        .filter_map(|p| find(data, "default", p, input, n, 1).map(|r| format!("{p} {:.2}×", spread(r).median / ours)))
        .collect();
    Some(format!(
        "On {} on one thread, `isolab.marching_cubes(method='lorensen')` takes {} ms (median); the others take, as a multiple \
         of that: {}.",
        label(input, n, data),
        ms(ours),
        peers.join(", ")
    ))
}

/// The page's opening reading: the headline of the largest gyroid and of the MNI template, then
/// which peers are faster or slower than ours on every input (one thread), and what the second
/// thread gives ours.
pub(super) fn reading(data: &Data) -> String {
    let all = inputs(data);
    let mut lines: Vec<String> = all
        .iter()
        .filter(|(input, n)| input != "gyroid" || *n == 256)
        .filter_map(|(input, n)| headline(data, input, *n))
        .collect();
    if lines.is_empty() {
        return String::new();
    }
    let ratios = |peer: &str| -> Vec<f64> {
        all.iter()
            .filter_map(|(input, n)| {
                let ours = spread(find(data, "default", OURS, input, *n, 1)?).median;
                Some(spread(find(data, "default", peer, input, *n, 1)?).median / ours)
            })
            .collect()
    };
    let (mut faster, mut slower, mut mixed) = (Vec::new(), Vec::new(), Vec::new());
    for peer in PEERS {
        let r = ratios(peer);
        if r.is_empty() {
            continue;
        }
        if r.iter().all(|&x| x < 1.0) {
            faster.push(peer);
        } else if r.iter().all(|&x| x > 1.0) {
            slower.push(peer);
        } else {
            mixed.push(peer);
        }
    }
    lines.push(format!(
        "Over all {} inputs on one thread, faster than ours on every one: {}; slower on every one: {}; either, by input: {}.",
        all.len(),
        crate::report::listed(&faster),
        crate::report::listed(&slower),
        crate::report::listed(&mixed)
    ));
    let second: Vec<f64> = all
        .iter()
        .filter_map(|(input, n)| {
            let one = spread(find(data, "default", OURS, input, *n, THREADS[0])?).median;
            Some(one / spread(find(data, "default", OURS, input, *n, THREADS[1])?).median)
        })
        .collect();
    if !second.is_empty() {
        let s = Spread::of(second);
        lines.push(format!(
            "Ours on {} threads: {:.2}× the one-thread speed, median over the inputs ({:.2}–{:.2}).",
            THREADS[1], s.median, s.min, s.max
        ));
    }
    lines.extend(targets::reading(data));
    lines.extend(targets::peak_reading(data));
    format!("**Reading.** {}\n\n", lines.join(" "))
}

pub(super) fn page_body(data: &Data) -> String {
    let mut md = String::from("## Marching cubes from Python, on a numpy array (`python_users`)\n\n");
    let two = THREADS[1];
    md.push_str(&format!(
        "What a researcher with a numpy array meets: each implementation called from one Python process on the same \
         array, one-shot (nothing kept between calls: a new VTK filter, a new zmesh `Mesher`), every conversion between \
         the user's array and the returned numpy arrays inside the timed call (what each converts and returns is \
         tabled below). Alternating: after one unrecorded warm-up round, every round calls each implementation once, in \
         an order rotated by one each round. {two} threads: isolab (`threads={two}`), VTK and pyvista (VTK's STDThread SMP \
         backend, `Initialize({two})`), and meshlib (TBB, which takes every core and has no setting, so it runs in these \
         rounds only, in rounds of its own after the others'); the others have no threads to give and run in the \
         one-thread rounds only. libigl takes its grid of sample positions as an argument, built outside the timed call, \
         and is not run where that grid alone would take gigabytes. The script is \
         `experiments/src/experiment/python_users/bench.py`, run in `tests/reference/.venv` after `pip install ./python` \
         of this commit.\n\n",
    ));
    md.push_str(&reading(data));
    md.push_str(&format!(
        "Rounds: {} per input ({} from {LARGE}³ on), in blocks: while any implementation's slowest call in a block took over \
         {wide}× its fastest, another block runs, up to {blocks} (\"(wide)\" marks a cell still wide after its last); ratios \
         round by round pair the calls of one round. Versions: {}.\n\n",
        data.repeats,
        data.large_repeats,
        data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", "),
        wide = crate::report::WIDE,
        blocks = crate::report::MAX_ROUNDS,
    ));
    md.push_str("### One thread\n\n");
    md.push_str(&timing_table(data, "default", THREADS[0]));
    md.push_str("\n![time against samples](figures/python_users/time-gyroid.png)\n\n");
    md.push_str(&format!("### {two} threads\n\n"));
    md.push_str(&timing_table(data, "default", two));
    md.push('\n');
    if data.rows.iter().any(|r| r.environment == HUGE_PAGES) {
        md.push_str(&format!(
            "### With huge pages for malloc\n\nThe same script in a second process started with \
             `GLIBC_TUNABLES={HUGE_PAGES_TUNABLE}` (glibc's malloc then asks the kernel for transparent huge pages, so \
             first touching a fresh buffer faults once per 2 MiB instead of once per 4 KiB), at the sizes where buffers are \
             largest. Every implementation's allocations are affected alike: for isolab, the arrays it returns (it reads \
             the input where it lies). numpy asks the kernel for huge pages for its own large arrays (by default, on Linux) whatever the \
             setting, so the inputs are alike in both runs.\n\n"
        ));
        for threads in THREADS {
            md.push_str(&format!("{} thread{}:\n\n", threads, if threads == 1 { "" } else { "s" }));
            md.push_str(&timing_table(data, HUGE_PAGES, threads));
            md.push('\n');
        }
    }
    md.push_str(&format!(
        "### Targets\n\nOurs is `isolab.marching_cubes(method='lorensen')` returning its four arrays; {} is VTK's flying edges \
         on the array's own buffer without normals; {} runs on one thread (it has no more to give), so our two-thread time \
         is held to its one-thread time. The floor is one read of the array and one write of our output's bytes into memory \
         touched before (both numpy, in the same process; a write into fresh memory, page faults included, is in the floors \
         table).\n\n",
        targets::VTK,
        targets::SKIMAGE
    ));
    md.push_str(&targets::table(data));
    md.push('\n');
    if !data.peaks.is_empty() {
        md.push_str(
            "### Peak memory\n\nEach implementation on each input in a process of its own, one call after a warm-up call on \
             a small block from the middle of the input: the resident high-water mark during the call less the resident \
             memory before it (which holds the input), beside the bytes of the arrays the call returns.\n\n",
        );
        md.push_str(&targets::peaks_table(data));
        md.push('\n');
    }
    if !data.floors.is_empty() {
        md.push_str("### Floors\n\n");
        let rows: Vec<Vec<String>> = data
            .floors
            .iter()
            .map(|f| {
                vec![
                    label(&f.input, f.n, data),
                    format!("{:.1}", f.output_bytes as f64 / (1u64 << 20) as f64),
                    ms(f.read_ms),
                    ms(f.write_ms),
                    ms(f.first_touch_write_ms),
                ]
            })
            .collect();
        md.push_str(&markdown_table(
            &["input", "our output, MiB", "read the array, ms", "write the output, ms", "write it into fresh memory, ms"],
            &rows,
        ));
        md.push('\n');
    }
    md.push_str("### Inputs\n\n");
    let rows: Vec<Vec<String>> = data
        .inputs
        .iter()
        .map(|i| vec![label(&i.input, i.n, data), i.dtype.clone(), i.order.clone(), format!("{:.4}", i.level)])
        .collect();
    md.push_str(&markdown_table(&["input", "dtype", "memory order", "level"], &rows));
    md.push_str(
        "\nThe gyroid is `sin x cos y + sin y cos z + sin z cos x` over three periods, sampled by numpy at the centres of n \
         samples a side; the MNI152 T1 template is the one nilearn ships, as `nibabel.load(path).get_fdata()` returns it, \
         at the level `isolab.extract` picks for the file (Otsu's threshold).\n\n",
    );
    md.push_str("### What each call returns and converts\n\n");
    let converts: Vec<Vec<String>> =
        crate::report::first_seen(data.rows.iter().map(|r| (r.implementation.clone(), r.returns.clone(), r.converts.clone())))
            .into_iter()
            .map(|(i, r, c)| vec![i, r, c])
            .collect();
    md.push_str(&markdown_table(&["implementation", "returns", "conversion, inside the timed call"], &converts));
    md.push_str(
        "\nzmesh meshes label volumes, not intensities: it is given the thresholded array and meshes that binary volume's \
         boundary (its triangle counts differ for that reason); its time includes the threshold.\n",
    );
    if !data.notes.is_empty() {
        md.push_str("\nNotes from the run: ");
        md.push_str(&data.notes.join("; "));
        md.push_str(".\n");
    }
    md
}
