//! Writers for both formats (docs/formats.md §7.3): vertices first, sorted by id, isolated
//! ones included; edges in input order; the FIX ids as one line at the end, where GTSAM's reader
//! tolerates it (docs/formats.md §5.6); every float in shortest round-trip form, never NaN or inf.

use super::{Dialect, Format, g2o, toro};
use crate::error::Error;
use crate::graph::PoseGraph;
use std::io::Write;

/// How to write a graph.
#[derive(Debug, Clone, Copy)]
pub struct WriteOptions {
    pub format: Format,
    /// Order of the noise values; its kind (information or covariance) must be the graph's.
    pub dialect: Dialect,
}

/// Appends the shortest decimal that parses back to exactly `v`, by the Żmij algorithm (the
/// `zmij` crate, several times faster than the standard library's formatting): plain notation
/// for 1e-5 <= |v| < 1e16 (without a trailing `.0`), exponent notation (`1e-7`, `1.5e+300`)
/// otherwise, so no number is longer than 24 bytes; C++ `>>` reads both. The sign of zero is kept.
pub fn format_f64(v: f64, out: &mut Vec<u8>) {
    debug_assert!(v.is_finite());
    let mut buffer = zmij::Buffer::new();
    let text = buffer.format_finite(v).as_bytes();
    out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
}

/// Writes `graph` to `out`.
pub fn write<W: Write>(graph: &PoseGraph, options: WriteOptions, out: W) -> crate::Result<()> {
    write_named(graph, options, out, "<stdout>")
}

fn write_named<W: Write>(
    graph: &PoseGraph,
    options: WriteOptions,
    mut out: W,
    name: &str,
) -> crate::Result<()> {
    if options.dialect.noise() != graph.noise {
        return Err(Error::Invalid(format!(
            "cannot write {:?} matrices in dialect {}",
            graph.noise, options.dialect
        )));
    }
    check_finite(graph)?;
    let (vertex_tag, edge_tag) = match options.format {
        Format::G2o => (g2o::VERTEX, g2o::EDGE),
        Format::Toro => (toro::VERTEX, toro::EDGE),
    };
    let io = |e| Error::io(name, e);
    // Lines are assembled in a buffer flushed in large chunks.
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let put = |buf: &mut Vec<u8>, out: &mut W| -> crate::Result<()> {
        if buf.len() >= 1 << 16 {
            out.write_all(buf).map_err(io)?;
            buf.clear();
        }
        Ok(())
    };
    for (id, pose) in graph.ids.iter().zip(&graph.poses) {
        buf.extend_from_slice(vertex_tag.as_bytes());
        let _ = write!(buf, " {id}");
        for v in pose.values() {
            buf.push(b' ');
            format_f64(v, &mut buf);
        }
        buf.push(b'\n');
        put(&mut buf, &mut out)?;
    }
    for e in &graph.edges {
        buf.extend_from_slice(edge_tag.as_bytes());
        let _ = write!(buf, " {} {}", graph.ids[e.i], graph.ids[e.j]);
        let noise = if options.dialect.toro_order() {
            e.noise.to_toro()
        } else {
            e.noise.0
        };
        for v in e.measurement.values().into_iter().chain(noise) {
            buf.push(b' ');
            format_f64(v, &mut buf);
        }
        buf.push(b'\n');
        put(&mut buf, &mut out)?;
    }
    if !graph.fixed.is_empty() {
        buf.extend_from_slice(g2o::FIX.as_bytes());
        for &k in &graph.fixed {
            let _ = write!(buf, " {}", graph.ids[k]);
        }
        buf.push(b'\n');
    }
    out.write_all(&buf).map_err(io)?;
    out.flush().map_err(io)
}

fn check_finite(graph: &PoseGraph) -> crate::Result<()> {
    if let Some(k) = graph
        .poses
        .iter()
        .position(|p| !p.values().iter().all(|v| v.is_finite()))
    {
        return Err(Error::Invalid(format!(
            "pose of vertex {} is not finite and cannot be written",
            graph.ids[k]
        )));
    }
    if let Some(e) = graph.edges.iter().find(|e| {
        !e.measurement
            .values()
            .iter()
            .chain(&e.noise.0)
            .all(|v| v.is_finite())
    }) {
        return Err(Error::Invalid(format!(
            "edge {} -> {} holds a value that is not finite and cannot be written",
            graph.ids[e.i], graph.ids[e.j]
        )));
    }
    Ok(())
}

/// Writes `graph` to `path` (stdout for `-`). A file is written to a temporary file in the same
/// directory and renamed over `path` only once complete, so a failure never leaves a partial or
/// truncated file.
pub fn write_path(graph: &PoseGraph, options: WriteOptions, path: &str) -> crate::Result<()> {
    if path == "-" {
        let stdout = std::io::stdout();
        return write_named(graph, options, stdout.lock(), "<stdout>");
    }
    let target = std::path::Path::new(path);
    // A device or a FIFO (/dev/null, /dev/stdout, a named pipe) is written in place: renaming a
    // temporary file over it would replace the device with a regular file.
    if let Ok(meta) = std::fs::metadata(target)
        && !meta.is_file()
        && !meta.is_dir()
    {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(target)
            .map_err(|e| Error::io(path, e))?;
        return write_named(graph, options, std::io::BufWriter::new(file), path);
    }
    if target.is_dir() {
        // Else the rename of the temporary file over it fails with a less telling message.
        return Err(Error::Invalid(format!("{path}: is a directory")));
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => std::path::Path::new("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(".pgo-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| Error::io(path, e))?;
    write_named(graph, options, std::io::BufWriter::new(tmp.as_file()), path)?;
    set_default_permissions(tmp.path()).map_err(|e| Error::io(path, e))?;
    tmp.persist(target).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// Temporary files are created private (0600); a written graph gets the usual 0644.
#[cfg(unix)]
fn set_default_permissions(path: &std::path::Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o644))
}

#[cfg(not(unix))]
fn set_default_permissions(_: &std::path::Path) -> std::io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt(v: f64) -> String {
        let mut out = Vec::new();
        format_f64(v, &mut out);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn shortest_round_trip() {
        assert_eq!(fmt(0.0), "0");
        assert_eq!(fmt(-0.0), "-0");
        assert_eq!(fmt(1.0), "1");
        assert_eq!(fmt(-0.5), "-0.5");
        assert_eq!(fmt(44.721359549995796), "44.721359549995796");
        assert_eq!(fmt(1e-7), "1e-7");
        assert_eq!(fmt(1e-5), "0.00001");
        assert_eq!(fmt(6.95335e-310), "6.95335e-310");
        assert_eq!(fmt(1.5e300), "1.5e+300");
        assert_eq!(fmt(1e16), "1e+16");
        assert_eq!(fmt(1e15), "1000000000000000");
        assert_eq!(fmt(-10.0), "-10");
        assert_eq!(fmt(123456789012345.6), "123456789012345.6");
        // Every value, including awkward ones, parses back to the same bits.
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                let s = fmt(v);
                assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
                assert!(s.len() <= 24, "{s}");
            }
        }
    }
}
