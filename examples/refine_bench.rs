//! Wall time of Levenberg-Marquardt under the files' information matrices (`pgo::refine`) on
//! public data sets, from the file's vertices (or a spanning tree when a file has none).
//!
//! ```text
//! cargo run --release --example refine_bench [-- [--max-iterations N] [--tree] FILE...]
//! ```
//!
//! Default files: M3500, intel, city10000 and ais2klinik from ../shared/datasets; `--tree`
//! starts every file from its spanning tree.

use pgo::io::{self, ReadOptions};
use pgo::refine::{RefineOptions, refine};
use std::time::Instant;

fn main() {
    let mut options = RefineOptions::default();
    let mut tree = false;
    let mut args = Vec::new();
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--max-iterations" => {
                options.max_iterations = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--max-iterations N")
            }
            "--tree" => tree = true,
            _ => args.push(a),
        }
    }
    let files = if args.is_empty() {
        ["M3500.g2o", "intel.g2o", "city10000.g2o", "ais2klinik.g2o"]
            .iter()
            .map(|f| format!("{}/../shared/datasets/{f}", env!("CARGO_MANIFEST_DIR")))
            .collect()
    } else {
        args
    };
    println!(
        "file\tposes\tedges\tstart\tchi2_initial\tchi2\titerations\tfactorizations\tstop\tread_s\trefine_s"
    );
    for path in files {
        let t = Instant::now();
        let mut g = match io::read_path(&path, &ReadOptions::default()) {
            Ok((g, _)) => g,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let read = t.elapsed().as_secs_f64();
        let start = if g.vertices_declared && !tree {
            "file"
        } else {
            g.initialize_spanning_tree();
            "tree"
        };
        let t = Instant::now();
        match refine(&g, &g.poses, &options) {
            Ok(r) => println!(
                "{path}\t{}\t{}\t{start}\t{}\t{}\t{}\t{}\t{:?}\t{read:.3}\t{:.3}",
                g.num_poses(),
                g.edges.len(),
                r.initial_chi2,
                r.chi2,
                r.iterations,
                r.factorizations,
                r.stop,
                t.elapsed().as_secs_f64()
            ),
            Err(e) => eprintln!("{path}: {e}"),
        }
    }
}
