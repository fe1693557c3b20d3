//! The certified SE(3) solver (issue 15, second landing).

mod common;

use pgo::graph3::Graph3;
use pgo::io::ReadOptions;
use pgo::se3::problem::weights3;
use pgo::se3::{Options3, solve_graph3};

fn read(name: &str) -> Graph3 {
    let path = common::datasets_dir().join(name);
    let bytes = std::fs::read(&path).unwrap();
    pgo::io::read3(&bytes, name, &ReadOptions::default())
        .unwrap()
        .0
}

#[test]
fn experiment() {
    for name in std::env::var("SE3_FILES")
        .unwrap_or("tinyGrid3D.g2o smallGrid3D.g2o".into())
        .split_whitespace()
    {
        let g = read(name);
        let w = weights3(&g, false).unwrap();
        let t = std::time::Instant::now();
        let s = solve_graph3(&g, &w, &Options3::default(), &mut |st| {
            eprintln!(
                "  rank {} it {} cost {:.12e} grad {:.3e} mu {:.1e}",
                st.rank, st.iteration, st.cost, st.gradient_norm, st.damping
            )
        });
        eprintln!(
            "{name}: cost {:.10e} lb {:.10e} certified {} rank {} it {} grad {:.2e} {:?} bound {:?} {:?}",
            s.cost,
            s.lower_bound,
            s.certified,
            s.rank,
            s.iterations,
            s.gradient_norm,
            s.not_certified_because,
            s.bound,
            t.elapsed()
        );
    }
}
