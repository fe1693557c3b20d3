//! Reads one file many times in one process and prints the median read time: a profiling aid
//! (`perf record target/release/examples/read_many FILE`), not a benchmark of record.
fn main() {
    let path = std::env::args().nth(1).expect("usage: read_many FILE [N]");
    let n: usize = std::env::args()
        .nth(2)
        .map_or(50, |s| s.parse().expect("N is a count"));
    let mut times = Vec::with_capacity(n);
    for _ in 0..n {
        let t = std::time::Instant::now();
        let (g, _) = pgo::io::read_path(&path, &Default::default()).expect("readable file");
        times.push(t.elapsed().as_secs_f64());
        std::hint::black_box(g);
    }
    times.sort_by(f64::total_cmp);
    println!("median read {:.3} ms over {n} reads", 1e3 * times[n / 2]);
}
