//! The 3D reader: g2o's `VERTEX_SE3:QUAT`/`EDGE_SE3:QUAT` and TORO's `VERTEX3`/`EDGE3`
//! (docs/formats.md §2.6, §3.4, §10), with the layout rules of the planar reader (comments, blank
//! lines, CRLF, tabs, a BOM, trailing `# comments`, FIX anywhere, vertices after edges) and its
//! strictness about values (every number finite and exactly representable, every id a valid
//! `int`, exactly the number of fields). Line by line over the whole input (3D files are small
//! next to the planar city-scale ones the planar reader's two threads are for), well-formed
//! vertex and edge lines in one pass over their bytes, as the planar reader reads them.
//!
//! Decided here (docs/formats.md §10): a quaternion is kept as written and stands for q / |q|
//! (g2o normalizes an edge's quaternion on reading); one that cannot be normalized is an error.
//! Information matrices: their translation and rotation blocks must be positive definite unless
//! `allow_indefinite` (SE-Sync's weights, τ from the translation block and κ from the rotation
//! block, need their inverses); a 6x6 matrix that is indefinite only through its off-diagonal
//! blocks is kept as read with a warning (g2o loads any matrix; cubicle.g2o has such edges). Edges must join declared vertices (GTSAM's `load3D` does not
//! invent them either). NaN and infinity are refused by the lexer, as in 2D.

use super::lexer::{Field, parse_f64, parse_id, scan_f64s, scan_id, skip_space, split_fields};
use super::options::ReadOptions;
use super::reader::ReadReport;
use super::{Dialect, Format, g2o, toro};
use crate::error::{Error, Location, ParseError, ParseErrorKind, Warning};
use crate::graph::VertexId;
use crate::graph3::{Edge3, Form3, Graph3, Pose3, Rotation3, SymMat6};

/// g2o's 3D pose vertex: `VERTEX_SE3:QUAT id x y z qx qy qz qw`.
pub const G2O_VERTEX: &str = "VERTEX_SE3:QUAT";
/// g2o's 3D relative-pose edge: `EDGE_SE3:QUAT i j x y z qx qy qz qw` + 21 information values.
pub const G2O_EDGE: &str = "EDGE_SE3:QUAT";
/// TORO's 3D pose vertex: `VERTEX3 id x y z roll pitch yaw`.
pub const TORO_VERTEX: &str = "VERTEX3";
/// TORO's 3D relative-pose edge: `EDGE3 i j x y z roll pitch yaw` + 21 information values.
pub const TORO_EDGE: &str = "EDGE3";

/// Planar tags, an error in a 3D file.
const PLANAR: &[&str] = &[
    g2o::VERTEX,
    g2o::EDGE,
    "VERTEX2",
    "VERTEX",
    "EDGE2",
    "EDGE",
    g2o::LANDMARK_VERTEX,
    g2o::LANDMARK_EDGE,
    g2o::LANDMARK2,
    g2o::POINT2,
];

#[cfg_attr(test, derive(Debug, PartialEq))]
struct RawVertex {
    id: VertexId,
    line: usize,
    col: usize,
    pose: Pose3,
}

#[cfg_attr(test, derive(Debug, PartialEq))]
struct RawEdge {
    i: VertexId,
    j: VertexId,
    measurement: Pose3,
    information: SymMat6,
    line: usize,
    col_i: usize,
    col_j: usize,
    col_noise: usize,
}

struct Parser<'a> {
    name: &'a str,
    options: &'a ReadOptions,
    vertices: Vec<RawVertex>,
    edges: Vec<RawEdge>,
    fixed: Vec<(VertexId, usize, usize)>,
    /// The first 3D line: its form, line and tag.
    first: Option<(Form3, usize, String)>,
    /// Unknown tags: (tag, first line, count).
    unknown: Vec<(String, usize, usize)>,
    equiv: Option<(usize, usize)>,
    /// The first planar line before any 3D line: its line and tag.
    first_planar: Option<(usize, String)>,
}

/// Reads a 3D pose graph from the whole input `bytes`; `name` is the path used in messages.
pub fn read3(
    bytes: &[u8],
    name: &str,
    options: &ReadOptions,
) -> crate::Result<(Graph3, ReadReport)> {
    let mut p = Parser {
        name,
        options,
        vertices: Vec::new(),
        edges: Vec::new(),
        fixed: Vec::new(),
        first: None,
        unknown: Vec::new(),
        equiv: None,
        first_planar: None,
    };
    let mut fields: Vec<Field> = Vec::with_capacity(32);
    for (k, raw) in bytes.split(|&c| c == b'\n').enumerate() {
        let line = if k == 0 {
            raw.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(raw)
        } else {
            raw
        };
        if !p.fast_line(k + 1, line) {
            split_fields(line, &mut fields);
            p.line(k + 1, line, &fields)?;
        }
    }
    // As the planar reader counts them: a final line without a newline counts.
    let lines = memchr::memchr_iter(b'\n', bytes).count()
        + usize::from(bytes.last().is_some_and(|&c| c != b'\n'));
    p.finish(lines)
}

/// How many values a pose of `form` has: x y z, then a quaternion (g2o) or three Euler angles
/// (TORO).
fn pose_values(form: Form3) -> usize {
    match form {
        Form3::G2o => 7,
        Form3::Toro => 6,
    }
}

/// The pose of the values `v` (x y z, then the rotation of `form`); `None` for a quaternion that
/// cannot be normalized.
fn pose_of(v: &[f64; 7], form: Form3) -> Option<Pose3> {
    let rotation = match form {
        Form3::G2o => {
            let q = [v[3], v[4], v[5], v[6]];
            let norm2: f64 = q.iter().map(|x| x * x).sum();
            if !(norm2 > 0.0 && norm2.is_finite()) {
                return None;
            }
            Rotation3::Quaternion(q)
        }
        Form3::Toro => Rotation3::Euler([v[3], v[4], v[5]]),
    };
    Some(Pose3 {
        translation: [v[0], v[1], v[2]],
        rotation,
    })
}

impl Parser<'_> {
    fn error(&self, line: usize, col: usize, kind: ParseErrorKind) -> ParseError {
        ParseError {
            location: Location {
                path: self.name.to_string(),
                line,
                col,
            },
            kind,
        }
    }

    fn line(&mut self, line_no: usize, line: &[u8], fields: &[Field]) -> Result<(), ParseError> {
        let Some(tag) = fields.first() else {
            return Ok(());
        };
        let text = tag.text;
        let is = |names: &[&str]| names.iter().any(|n| n.as_bytes() == text);
        if text.first() == Some(&b'#') {
            Ok(())
        } else if text == G2O_VERTEX.as_bytes() {
            self.vertex(line_no, line, fields, Form3::G2o)
        } else if text == TORO_VERTEX.as_bytes() {
            self.vertex(line_no, line, fields, Form3::Toro)
        } else if text == G2O_EDGE.as_bytes() {
            self.edge(line_no, line, fields, Form3::G2o)
        } else if text == TORO_EDGE.as_bytes() {
            self.edge(line_no, line, fields, Form3::Toro)
        } else if text == g2o::FIX.as_bytes() {
            self.fix(line_no, fields)
        } else if is(PLANAR) {
            if let Some((_, first_line, first)) = &self.first {
                return Err(self.error(
                    line_no,
                    tag.col,
                    ParseErrorKind::MixedDimensions {
                        first: first.clone(),
                        first_line: *first_line,
                        tag: tag.lossy(),
                    },
                ));
            }
            self.first_planar
                .get_or_insert_with(|| (line_no, tag.lossy()));
            Ok(())
        } else if is(g2o::THREE_D) {
            Err(self.error(
                line_no,
                tag.col,
                ParseErrorKind::Unsupported3D { tag: tag.lossy() },
            ))
        } else if text == toro::EQUIV.as_bytes() {
            if self.options.strict || !self.options.ignore_equiv {
                return Err(self.error(line_no, tag.col, ParseErrorKind::Equiv));
            }
            let e = self.equiv.get_or_insert((line_no, 0));
            e.1 += 1;
            Ok(())
        } else {
            let name = tag.lossy();
            if self.options.strict {
                return Err(self.error(line_no, tag.col, ParseErrorKind::UnknownTag { tag: name }));
            }
            match self.unknown.iter_mut().find(|(t, _, _)| *t == name) {
                Some((_, _, count)) => *count += 1,
                None => self.unknown.push((name, line_no, 1)),
            }
            Ok(())
        }
    }

    /// Notes the form of a 3D line; a line of the other form than the first is an error.
    fn form(&mut self, form: Form3, line_no: usize, tag: &Field) -> Result<(), ParseError> {
        if let Some((first_line, first)) = &self.first_planar {
            return Err(self.error(
                line_no,
                tag.col,
                ParseErrorKind::MixedDimensions {
                    first: first.clone(),
                    first_line: *first_line,
                    tag: tag.lossy(),
                },
            ));
        }
        match &self.first {
            None => {
                self.first = Some((form, line_no, tag.lossy()));
                Ok(())
            }
            Some((f, _, _)) if *f == form => Ok(()),
            Some((_, first_line, first)) => Err(self.error(
                line_no,
                tag.col,
                ParseErrorKind::Mixed3dForms {
                    first: first.clone(),
                    first_line: *first_line,
                    tag: tag.lossy(),
                },
            )),
        }
    }

    /// The fields after the tag, exactly `expected` of them before an optional `# comment`.
    fn args<'f, 'a>(
        &self,
        line_no: usize,
        line: &[u8],
        fields: &'f [Field<'a>],
        expected: usize,
        layout: &'static str,
    ) -> Result<&'f [Field<'a>], ParseError> {
        let args = &fields[1..];
        let used = args
            .iter()
            .position(|f| f.text.first() == Some(&b'#'))
            .unwrap_or(args.len());
        if used == expected {
            return Ok(&args[..expected]);
        }
        let col = if used < expected {
            line.iter()
                .rposition(|c| !c.is_ascii_whitespace())
                .map_or(1, |p| p + 2)
        } else {
            args[expected].col
        };
        Err(self.error(
            line_no,
            col,
            ParseErrorKind::FieldCount {
                tag: fields[0].lossy(),
                expected,
                found: used,
                layout,
            },
        ))
    }

    fn num(&self, line_no: usize, f: &Field) -> Result<f64, ParseError> {
        parse_f64(f).map_err(|k| self.error(line_no, f.col, k))
    }

    fn id(&self, line_no: usize, f: &Field) -> Result<VertexId, ParseError> {
        parse_id(f).map_err(|k| self.error(line_no, f.col, k))
    }

    /// A pose from its fields (x y z, then the rotation of `form`).
    fn pose(&self, line_no: usize, a: &[Field], form: Form3) -> Result<Pose3, ParseError> {
        let mut v = [0.0; 7];
        for (x, f) in v[..pose_values(form)].iter_mut().zip(a) {
            *x = self.num(line_no, f)?;
        }
        pose_of(&v, form)
            .ok_or_else(|| self.error(line_no, a[3].col, ParseErrorKind::BadQuaternion))
    }

    /// The hot path, as the planar reader's (`block.rs`): a well-formed vertex or edge line of
    /// the form the file began with, in one pass over its bytes. Returns false, having recorded
    /// nothing, for any other line or anything unusual in it (the first 3D line, a `# comment`
    /// after the values, a number outside Clinger's fast path, a quaternion that cannot be
    /// normalized, a self-loop): [`Self::line`] then reads it, and reports what is wrong. The
    /// values are those of the general path, which takes the same scanner first.
    fn fast_line(&mut self, line_no: usize, line: &[u8]) -> bool {
        let mut s = line;
        skip_space(&mut s);
        let tag_len = s.iter().take_while(|c| !c.is_ascii_whitespace()).count();
        let (tag, mut s) = s.split_at(tag_len);
        let (form, vertex) = match tag {
            t if t == G2O_VERTEX.as_bytes() => (Form3::G2o, true),
            t if t == G2O_EDGE.as_bytes() => (Form3::G2o, false),
            t if t == TORO_VERTEX.as_bytes() => (Form3::Toro, true),
            t if t == TORO_EDGE.as_bytes() => (Form3::Toro, false),
            _ => return false,
        };
        if self.first_planar.is_some() || !matches!(&self.first, Some((f, _, _)) if *f == form) {
            return false;
        }
        let col = |s: &[u8]| line.len() - s.len() + 1;
        let mut ids = [(0, 0); 2];
        for id in &mut ids[..if vertex { 1 } else { 2 }] {
            skip_space(&mut s);
            let at = col(s);
            let Some(value) = scan_id(&mut s) else {
                return false;
            };
            *id = (value, at);
        }
        let mut v = [0.0; 7];
        if !scan_f64s(&mut s, &mut v[..pose_values(form)]) {
            return false;
        }
        let mut info = [0.0; 21];
        let mut col_noise = 0;
        if !vertex {
            skip_space(&mut s);
            col_noise = col(s);
            if !scan_f64s(&mut s, &mut info) {
                return false;
            }
        }
        skip_space(&mut s);
        let Some(pose) = pose_of(&v, form).filter(|_| s.is_empty()) else {
            return false;
        };
        let [(i, col_i), (j, col_j)] = ids;
        if vertex {
            self.vertices.push(RawVertex {
                id: i,
                line: line_no,
                col: col_i,
                pose,
            });
        } else {
            if i == j {
                return false;
            }
            self.edges.push(RawEdge {
                i,
                j,
                measurement: pose,
                information: SymMat6(info),
                line: line_no,
                col_i,
                col_j,
                col_noise,
            });
        }
        true
    }

    fn vertex(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        form: Form3,
    ) -> Result<(), ParseError> {
        let (count, layout) = match form {
            Form3::G2o => (8, "id x y z qx qy qz qw"),
            Form3::Toro => (7, "id x y z roll pitch yaw"),
        };
        self.form(form, line_no, &fields[0])?;
        let a = self.args(line_no, line, fields, count, layout)?;
        let id = self.id(line_no, &a[0])?;
        let pose = self.pose(line_no, &a[1..], form)?;
        self.vertices.push(RawVertex {
            id,
            line: line_no,
            col: a[0].col,
            pose,
        });
        Ok(())
    }

    fn edge(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        form: Form3,
    ) -> Result<(), ParseError> {
        let (count, layout, rotation) = match form {
            Form3::G2o => (
                30,
                "i j x y z qx qy qz qw and 21 information values, the upper triangle row by row over x y z qx qy qz",
                4,
            ),
            Form3::Toro => (
                29,
                "i j x y z roll pitch yaw and 21 information values, the upper triangle row by row over x y z roll pitch yaw",
                3,
            ),
        };
        self.form(form, line_no, &fields[0])?;
        let a = self.args(line_no, line, fields, count, layout)?;
        let i = self.id(line_no, &a[0])?;
        let j = self.id(line_no, &a[1])?;
        let measurement = self.pose(line_no, &a[2..], form)?;
        let noise = &a[5 + rotation..];
        let mut info = [0.0; 21];
        for (x, f) in info.iter_mut().zip(noise) {
            *x = self.num(line_no, f)?;
        }
        if i == j {
            return Err(self.error(line_no, a[1].col, ParseErrorKind::SelfLoop { id: i }));
        }
        self.edges.push(RawEdge {
            i,
            j,
            measurement,
            information: SymMat6(info),
            line: line_no,
            col_i: a[0].col,
            col_j: a[1].col,
            col_noise: noise[0].col,
        });
        Ok(())
    }

    fn fix(&mut self, line_no: usize, fields: &[Field]) -> Result<(), ParseError> {
        let args: Vec<&Field> = fields[1..]
            .iter()
            .take_while(|f| f.text.first() != Some(&b'#'))
            .collect();
        if args.is_empty() {
            let col = fields[0].col + fields[0].text.len();
            return Err(self.error(line_no, col, ParseErrorKind::NoFixIds));
        }
        for f in args {
            let id = self.id(line_no, f)?;
            self.fixed.push((id, line_no, f.col));
        }
        Ok(())
    }

    fn warning(&self, line: usize, message: String) -> Warning {
        Warning {
            location: Location {
                path: self.name.to_string(),
                line,
                col: 1,
            },
            message,
        }
    }

    fn finish(self, lines: usize) -> crate::Result<(Graph3, ReadReport)> {
        let Some((form, _, _)) = self.first.clone() else {
            return Err(self
                .error(1, 1, ParseErrorKind::NoGraph { empty: lines == 0 })
                .into());
        };
        let (format, dialect, edge_tag) = match form {
            Form3::G2o => (Format::G2o, Dialect::G2o, G2O_EDGE),
            Form3::Toro => (Format::Toro, Dialect::ToroInfo, TORO_EDGE),
        };
        if let Some(d) = self.options.dialect
            && d != dialect
        {
            return Err(Error::Invalid(format!(
                "{}: dialect {d} does not apply to a 3D file: its {edge_tag} lines hold information matrices, the upper triangle row by row (dialect {dialect})",
                self.name
            )));
        }
        // Vertices sorted by id (stable: the lines of one id stay in file order); the duplicate
        // declared earliest in the file is reported.
        let v = &self.vertices;
        let mut order: Vec<usize> = (0..v.len()).collect();
        order.sort_by_key(|&k| v[k].id);
        if let Some(w) = order
            .windows(2)
            .filter(|w| v[w[0]].id == v[w[1]].id)
            .min_by_key(|w| w[1])
        {
            let (first, second) = (&v[w[0]], &v[w[1]]);
            return Err(self
                .error(
                    second.line,
                    second.col,
                    ParseErrorKind::DuplicateVertex {
                        id: second.id,
                        first_line: first.line,
                    },
                )
                .into());
        }
        let ids: Vec<VertexId> = order.iter().map(|&k| v[k].id).collect();
        let poses: Vec<Pose3> = order.iter().map(|&k| v[k].pose).collect();
        let index = |id: VertexId| ids.binary_search(&id).ok();
        let mut edges = Vec::with_capacity(self.edges.len());
        // Edges whose 6x6 information is indefinite with definite blocks: (first line, count).
        let mut indefinite: Option<(usize, usize)> = None;
        for e in &self.edges {
            let i = index(e.i).ok_or_else(|| {
                self.error(
                    e.line,
                    e.col_i,
                    ParseErrorKind::UndeclaredVertex { id: e.i },
                )
            })?;
            let j = index(e.j).ok_or_else(|| {
                self.error(
                    e.line,
                    e.col_j,
                    ParseErrorKind::UndeclaredVertex { id: e.j },
                )
            })?;
            if !self.options.allow_indefinite {
                for (at, block) in [(0, "translation (x y z)"), (3, "rotation")] {
                    if let Err(pivot) = e.information.block(at).check_positive_definite() {
                        return Err(self
                            .error(
                                e.line,
                                e.col_noise,
                                ParseErrorKind::BlockNotPositiveDefinite { block, pivot },
                            )
                            .into());
                    }
                }
                if e.information.check_positive_definite().is_err() {
                    let w = indefinite.get_or_insert((e.line, 0));
                    w.1 += 1;
                }
            }
            edges.push(Edge3 {
                i,
                j,
                measurement: e.measurement,
                information: e.information,
            });
        }
        let mut fixed = Vec::with_capacity(self.fixed.len());
        let mut is_fixed = vec![false; ids.len()];
        for &(id, line, col) in &self.fixed {
            let k = index(id)
                .ok_or_else(|| self.error(line, col, ParseErrorKind::UnknownFixed { id }))?;
            if !std::mem::replace(&mut is_fixed[k], true) {
                fixed.push(k);
            }
        }
        let mut warnings = Vec::new();
        for (tag, first_line, count) in &self.unknown {
            let lines = if *count == 1 {
                "1 line".to_string()
            } else {
                format!("{count} lines")
            };
            warnings.push(self.warning(
                *first_line,
                format!("unknown tag '{tag}': {lines} skipped (first here)"),
            ));
        }
        if let Some((first_line, count)) = self.equiv {
            let lines = if count == 1 {
                "1 line".to_string()
            } else {
                format!("{count} lines")
            };
            warnings.push(self.warning(
                first_line,
                format!(
                    "EQUIV (vertex equivalence) is not supported: {lines} skipped (first here); the graph is read without them"
                ),
            ));
        }
        if let Some((first_line, count)) = indefinite {
            let edges = if count == 1 {
                "1 edge".to_string()
            } else {
                format!("{count} edges")
            };
            warnings.push(self.warning(
                first_line,
                format!(
                    "{edges} with an information matrix that is not positive definite as a whole, though its translation and rotation blocks are (first here): kept as read, as g2o reads them"
                ),
            ));
        }
        warnings.sort_by_key(|w| w.location.line);
        let graph = Graph3 {
            ids,
            poses,
            edges,
            fixed,
            form,
        };
        let report = ReadReport {
            format,
            format_reason: "tags",
            dialect,
            dialect_reason: match form {
                Form3::G2o => format!("3D: {G2O_VERTEX} and {G2O_EDGE} tags"),
                Form3::Toro => format!("3D: {TORO_VERTEX} and {TORO_EDGE} tags"),
            },
            warnings,
            lines,
            // Only `--robust` reads these (planar graphs).
            edge_lines: Vec::new(),
            vertigo: None,
        };
        Ok((graph, report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parser(options: &ReadOptions, form: Form3) -> Parser<'_> {
        Parser {
            name: "test.g2o",
            options,
            vertices: Vec::new(),
            edges: Vec::new(),
            fixed: Vec::new(),
            first: Some((form, 1, "the first line".into())),
            unknown: Vec::new(),
            equiv: None,
            first_planar: None,
        }
    }

    /// Whether the fast path takes `line`; when it does, it must record what the general path
    /// records from the same line (values, ids, columns), bit for bit.
    fn fast_matches_general(line: &str, form: Form3) -> bool {
        let options = ReadOptions::default();
        let (mut fast, mut general) = (parser(&options, form), parser(&options, form));
        let taken = fast.fast_line(7, line.as_bytes());
        let mut fields = Vec::new();
        split_fields(line.as_bytes(), &mut fields);
        let read = general.line(7, line.as_bytes(), &fields);
        if taken {
            assert!(
                read.is_ok(),
                "{line}: the general path refuses it: {read:?}"
            );
            assert_eq!(fast.vertices, general.vertices, "{line}");
            assert_eq!(fast.edges, general.edges, "{line}");
        } else {
            assert!(fast.vertices.is_empty() && fast.edges.is_empty(), "{line}");
        }
        taken
    }

    /// The one-pass path against the field-by-field one on well-formed lines of both forms
    /// (signs, exponents, leading zeros, tabs, CRLF, 19 digits), and lines it must leave to the
    /// general path (a trailing comment, 20 digits, a significand above 2^53, a zero quaternion,
    /// a self-loop, a missing or extra value, a negative id).
    #[test]
    fn the_fast_path_reads_what_the_general_path_reads() {
        let info = "100 0 0 0 0 0 100 0 0 0 0 100 0 0 0 400 0 0 400 0 400";
        for line in [
            "VERTEX_SE3:QUAT 12 1.5 -2.25e-3 +3 0 0 0.7071067811865476 0.7071067811865475",
            "  VERTEX_SE3:QUAT\t0\t0 0 0 0 0 0 1\r",
            "VERTEX_SE3:QUAT 000123456 0.000000000000000001 1E22 -0.0 0.5 0.5 0.5 0.5",
            &format!("EDGE_SE3:QUAT 3 4 1 2 3 0.1 0.2 0.3 0.9 {info}"),
            &format!("EDGE_SE3:QUAT 4 3 -1e-5 2E+2 .5 0 0 -1 0 {info}\r"),
        ] {
            assert!(fast_matches_general(line, Form3::G2o), "{line}");
        }
        for line in [
            "VERTEX3 5 1 2 3 0.1 -0.2 3.14159",
            &format!("EDGE3 5 6 1 0 0 0 0 1.570796326794897 {info}"),
        ] {
            assert!(fast_matches_general(line, Form3::Toro), "{line}");
        }
        for line in [
            "VERTEX_SE3:QUAT 1 0 0 0 0 0 0 1 # a comment",
            "VERTEX_SE3:QUAT 1 0 0 0 0 0 0 12345678901234567890",
            "VERTEX_SE3:QUAT 1 0 0 0 0 0 0.70710678118654752 0.7071067811865476",
            "VERTEX_SE3:QUAT 1 0 0 0 0 0 0 0",
            "VERTEX_SE3:QUAT 1 0 0 0 0 0 0",
            "VERTEX_SE3:QUAT 1 0 0 0 0 0 0 1 2",
            "VERTEX_SE3:QUAT -1 0 0 0 0 0 0 1",
            "VERTEX3 1 0 0 0 0 0 0",
            &format!("EDGE_SE3:QUAT 3 3 1 2 3 0 0 0 1 {info}"),
            &format!("EDGE_SE3:QUAT 3 4 1 2 3 0 0 0 1 {info} 1"),
            "EDGE_SE3:QUAT 3 4 1 2 3 0 0 0 1 1 2 3",
        ] {
            assert!(!fast_matches_general(line, Form3::G2o), "{line}");
        }
    }
}
