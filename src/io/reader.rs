//! The line reader shared by g2o and TORO files: both formats' pose tags are accepted in either
//! (as GTSAM does); how the six noise values are read is decided per file by the dialect
//! (FORMATS.md §7.2), never per tag.

use super::lexer::{Field, parse_f64, parse_id, split_fields};
use super::{Dialect, Format, g2o, toro};
use crate::error::{Location, ParseError, ParseErrorKind, Warning};
use crate::graph::{Edge, Pose2, PoseGraph, SymMat3, VertexId};
use std::collections::HashMap;
use std::io::BufRead;

/// How to read a file.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// The format; `None`: by extension, else by the first pose tag.
    pub format: Option<Format>,
    /// The dialect; `None`: by the edge tags (see [`ReadReport::dialect_reason`]).
    pub dialect: Option<Dialect>,
    /// Unknown tags and EQUIV lines are errors instead of warnings.
    pub strict: bool,
    /// Accept noise matrices that are not positive definite.
    pub allow_indefinite: bool,
}

/// What the reader decided and noticed.
#[derive(Debug, Clone)]
pub struct ReadReport {
    pub format: Format,
    /// Why: "flag", "extension" or "tags".
    pub format_reason: &'static str,
    pub dialect: Dialect,
    /// Why, in words (e.g. "EDGE_SE2 tags").
    pub dialect_reason: String,
    pub warnings: Vec<Warning>,
    /// Number of lines read.
    pub lines: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Family {
    G2o,
    Toro,
}

enum Tag {
    Vertex(Family),
    Edge(Family),
    Fix,
    Equiv,
    ThreeD,
    Landmark,
    Prior,
    Comment,
    Unknown,
}

fn classify(tag: &[u8]) -> Tag {
    let is = |names: &[&str]| names.iter().any(|n| n.as_bytes() == tag);
    if tag.first() == Some(&b'#') {
        Tag::Comment
    } else if tag == g2o::VERTEX.as_bytes() {
        Tag::Vertex(Family::G2o)
    } else if tag == g2o::EDGE.as_bytes() {
        Tag::Edge(Family::G2o)
    } else if is(toro::VERTEX_TAGS) {
        Tag::Vertex(Family::Toro)
    } else if is(toro::EDGE_TAGS) {
        Tag::Edge(Family::Toro)
    } else if tag == g2o::FIX.as_bytes() {
        Tag::Fix
    } else if tag == toro::EQUIV.as_bytes() {
        Tag::Equiv
    } else if is(g2o::THREE_D) || is(toro::THREE_D) {
        Tag::ThreeD
    } else if is(g2o::LANDMARK) || is(toro::LANDMARK) {
        Tag::Landmark
    } else if is(g2o::PRIOR) {
        Tag::Prior
    } else {
        Tag::Unknown
    }
}

struct RawVertex {
    id: VertexId,
    pose: Pose2,
    line: usize,
    col: usize,
}

/// An edge line before ids are resolved and before the dialect is known.
struct RawEdge {
    i: VertexId,
    j: VertexId,
    z: Pose2,
    /// The six noise values in file order.
    values: [f64; 6],
}

/// Where an edge line's fields are, for messages after the whole file is read.
struct EdgeSite {
    line: usize,
    col_i: usize,
    col_j: usize,
    col_noise: usize,
}

struct Skipped {
    first_line: usize,
    count: usize,
}

/// Reads a pose graph from a file path, or from stdin when `path` is `-`.
pub fn read_path(path: &str, options: &ReadOptions) -> crate::Result<(PoseGraph, ReadReport)> {
    if path == "-" {
        let stdin = std::io::stdin();
        return read(stdin.lock(), "<stdin>", options);
    }
    let file = std::fs::File::open(path).map_err(|e| crate::Error::io(path, e))?;
    let reader = std::io::BufReader::with_capacity(1 << 16, file);
    read(reader, path, options)
}

/// Reads a pose graph from `input`; `name` is the path used in messages and for the extension.
pub fn read<R: BufRead>(
    input: R,
    name: &str,
    options: &ReadOptions,
) -> crate::Result<(PoseGraph, ReadReport)> {
    let mut r = Reader::new(name, options);
    r.read_lines(input)?;
    Ok(r.finish()?)
}

struct Reader<'o> {
    name: String,
    options: &'o ReadOptions,
    vertices: Vec<RawVertex>,
    edges: Vec<RawEdge>,
    sites: Vec<EdgeSite>,
    fixed: Vec<(VertexId, usize, usize)>,
    /// The first edge tag: its family, line and spelling.
    first_edge_tag: Option<(Family, usize, String)>,
    first_vertex_family: Option<Family>,
    unknown: Vec<(String, Skipped)>,
    equiv: Option<Skipped>,
    lines: usize,
}

impl<'o> Reader<'o> {
    fn new(name: &str, options: &'o ReadOptions) -> Self {
        Reader {
            name: name.to_string(),
            options,
            vertices: Vec::new(),
            edges: Vec::new(),
            sites: Vec::new(),
            fixed: Vec::new(),
            first_edge_tag: None,
            first_vertex_family: None,
            unknown: Vec::new(),
            equiv: None,
            lines: 0,
        }
    }

    fn error(&self, line: usize, col: usize, kind: ParseErrorKind) -> ParseError {
        ParseError {
            location: Location {
                path: self.name.clone(),
                line,
                col,
            },
            kind,
        }
    }

    fn read_lines<R: BufRead>(&mut self, mut input: R) -> crate::Result<()> {
        let mut buf = Vec::with_capacity(256);
        // Field storage reused across lines (see `recycle`).
        let mut spare: Vec<Field<'static>> = Vec::with_capacity(16);
        let mut line_no = 0;
        loop {
            buf.clear();
            let n = input
                .read_until(b'\n', &mut buf)
                .map_err(|e| crate::Error::io(self.name.clone(), e))?;
            if n == 0 {
                break;
            }
            line_no += 1;
            let mut line: &[u8] = &buf;
            if line_no == 1 {
                line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
            }
            let mut fields = recycle(std::mem::take(&mut spare));
            split_fields(line, &mut fields);
            self.line(line_no, line, &fields)?;
            spare = recycle(fields);
        }
        self.lines = line_no;
        Ok(())
    }

    fn line(&mut self, line_no: usize, line: &[u8], fields: &[Field]) -> Result<(), ParseError> {
        let Some(tag) = fields.first() else {
            return Ok(());
        };
        let tag_name = || tag.lossy();
        let at_tag = |kind| self.error(line_no, tag.col, kind);
        match classify(tag.text) {
            Tag::Comment => Ok(()),
            Tag::Vertex(family) => self.vertex(line_no, line, fields, family),
            Tag::Edge(family) => self.edge(line_no, line, fields, family),
            Tag::Fix => self.fix(line_no, line, fields),
            Tag::Equiv => {
                if self.options.strict {
                    return Err(at_tag(ParseErrorKind::Equiv));
                }
                let e = self.equiv.get_or_insert(Skipped {
                    first_line: line_no,
                    count: 0,
                });
                e.count += 1;
                Ok(())
            }
            Tag::ThreeD => Err(at_tag(ParseErrorKind::ThreeD { tag: tag_name() })),
            Tag::Landmark => Err(at_tag(ParseErrorKind::Landmark { tag: tag_name() })),
            Tag::Prior => Err(at_tag(ParseErrorKind::Prior { tag: tag_name() })),
            Tag::Unknown => {
                let name = tag_name();
                if self.options.strict {
                    return Err(at_tag(ParseErrorKind::UnknownTag { tag: name }));
                }
                match self.unknown.iter_mut().find(|(t, _)| *t == name) {
                    Some((_, s)) => s.count += 1,
                    None => self.unknown.push((
                        name,
                        Skipped {
                            first_line: line_no,
                            count: 1,
                        },
                    )),
                }
                Ok(())
            }
        }
    }

    /// Checks the number of fields after the tag; a trailing `# comment` is allowed.
    fn expect_fields<'f, 'a>(
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
        let kind = ParseErrorKind::FieldCount {
            tag: fields[0].lossy(),
            expected,
            found: used,
            layout,
        };
        // Too few: point just past the last character; too many: at the first extra field.
        let col = if used < expected {
            line.iter()
                .rposition(|c| !c.is_ascii_whitespace())
                .map_or(1, |p| p + 2)
        } else {
            args[expected].col
        };
        Err(self.error(line_no, col, kind))
    }

    fn num(&self, line_no: usize, f: &Field) -> Result<f64, ParseError> {
        parse_f64(f).map_err(|k| self.error(line_no, f.col, k))
    }

    fn id(&self, line_no: usize, f: &Field) -> Result<VertexId, ParseError> {
        parse_id(f).map_err(|k| self.error(line_no, f.col, k))
    }

    fn vertex(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        family: Family,
    ) -> Result<(), ParseError> {
        let a = self.expect_fields(line_no, line, fields, 4, "id x y theta")?;
        let id = self.id(line_no, &a[0])?;
        let pose = Pose2::new(
            self.num(line_no, &a[1])?,
            self.num(line_no, &a[2])?,
            self.num(line_no, &a[3])?,
        );
        self.first_vertex_family.get_or_insert(family);
        self.vertices.push(RawVertex {
            id,
            pose,
            line: line_no,
            col: a[0].col,
        });
        Ok(())
    }

    fn edge(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        family: Family,
    ) -> Result<(), ParseError> {
        let layout = match family {
            Family::G2o => "i j dx dy dtheta and 6 noise values I11 I12 I13 I22 I23 I33",
            Family::Toro => "i j dx dy dtheta and 6 noise values ff fs ss rr fr sr",
        };
        let a = self.expect_fields(line_no, line, fields, 11, layout)?;
        let i = self.id(line_no, &a[0])?;
        let j = self.id(line_no, &a[1])?;
        let z = Pose2::new(
            self.num(line_no, &a[2])?,
            self.num(line_no, &a[3])?,
            self.num(line_no, &a[4])?,
        );
        let mut values = [0.0; 6];
        for (v, f) in values.iter_mut().zip(&a[5..11]) {
            *v = self.num(line_no, f)?;
        }
        if i == j {
            return Err(self.error(line_no, a[1].col, ParseErrorKind::SelfLoop { id: i }));
        }
        match &self.first_edge_tag {
            None => self.first_edge_tag = Some((family, line_no, fields[0].lossy())),
            Some((first, first_line, first_tag))
                if *first != family && self.options.dialect.is_none() =>
            {
                return Err(self.error(
                    line_no,
                    fields[0].col,
                    ParseErrorKind::MixedTags {
                        first: first_tag.clone(),
                        first_line: *first_line,
                        tag: fields[0].lossy(),
                    },
                ));
            }
            Some(_) => {}
        }
        self.edges.push(RawEdge { i, j, z, values });
        self.sites.push(EdgeSite {
            line: line_no,
            col_i: a[0].col,
            col_j: a[1].col,
            col_noise: a[5].col,
        });
        Ok(())
    }

    fn fix(&mut self, line_no: usize, line: &[u8], fields: &[Field]) -> Result<(), ParseError> {
        let args: Vec<&Field> = fields[1..]
            .iter()
            .take_while(|f| f.text.first() != Some(&b'#'))
            .collect();
        if args.is_empty() {
            return Err(self.error(
                line_no,
                line.len() + 1,
                ParseErrorKind::FieldCount {
                    tag: "FIX".into(),
                    expected: 1,
                    found: 0,
                    layout: "one or more vertex ids",
                },
            ));
        }
        for f in args {
            let id = self.id(line_no, f)?;
            self.fixed.push((id, line_no, f.col));
        }
        Ok(())
    }

    fn finish(self) -> Result<(PoseGraph, ReadReport), ParseError> {
        let (format, format_reason) = self.decide_format();
        let mut warnings = Vec::new();
        let declared = !self.vertices.is_empty();
        let (ids, poses) = self.vertex_table()?;
        let index = IdIndex::new(&ids);

        let mut edges = Vec::with_capacity(self.edges.len());
        for (e, site) in self.edges.iter().zip(&self.sites) {
            let (i, j) = match (index.get(e.i), index.get(e.j)) {
                (Some(i), Some(j)) => (i, j),
                (None, _) => {
                    return Err(self.error(
                        site.line,
                        site.col_i,
                        ParseErrorKind::UndeclaredVertex { id: e.i },
                    ));
                }
                (_, None) => {
                    return Err(self.error(
                        site.line,
                        site.col_j,
                        ParseErrorKind::UndeclaredVertex { id: e.j },
                    ));
                }
            };
            edges.push(Edge {
                i,
                j,
                measurement: e.z,
                noise: SymMat3::IDENTITY,
            });
        }

        let mut fixed = Vec::with_capacity(self.fixed.len());
        for &(id, line, col) in &self.fixed {
            let k = index
                .get(id)
                .ok_or_else(|| self.error(line, col, ParseErrorKind::UnknownFixed { id }))?;
            if !fixed.contains(&k) {
                fixed.push(k);
            }
        }

        let (dialect, dialect_reason) = self.decide_dialect(format, &mut warnings);
        for (edge, raw) in edges.iter_mut().zip(&self.edges) {
            edge.noise = noise_matrix(raw.values, dialect);
        }
        if !self.options.allow_indefinite {
            self.check_positive_definite(&edges, dialect)?;
        }

        for (tag, s) in &self.unknown {
            warnings.push(self.warning(
                s.first_line,
                format!(
                    "unknown tag '{tag}': {} skipped (first here)",
                    plural(s.count, "line")
                ),
            ));
        }
        if let Some(s) = &self.equiv {
            warnings.push(self.warning(
                s.first_line,
                format!(
                    "EQUIV (vertex equivalence) is not supported: {} skipped (first here)",
                    plural(s.count, "line")
                ),
            ));
        }
        warnings.sort_by_key(|w| w.location.line);

        let mut graph = PoseGraph {
            ids,
            poses,
            edges,
            fixed,
            vertices_declared: declared,
            noise: dialect.noise(),
        };
        if !declared {
            graph.initialize_spanning_tree();
        }
        let report = ReadReport {
            format,
            format_reason,
            dialect,
            dialect_reason,
            warnings,
            lines: self.lines,
        };
        Ok((graph, report))
    }

    fn warning(&self, line: usize, message: String) -> Warning {
        Warning {
            location: Location {
                path: self.name.clone(),
                line,
                col: 1,
            },
            message,
        }
    }

    fn decide_format(&self) -> (Format, &'static str) {
        if let Some(f) = self.options.format {
            return (f, "flag");
        }
        if let Some(f) = Format::from_extension(&self.name) {
            return (f, "extension");
        }
        let family = self
            .first_vertex_family
            .or(self.first_edge_tag.as_ref().map(|t| t.0));
        match family {
            Some(Family::Toro) => (Format::Toro, "tags"),
            _ => (Format::G2o, "tags"),
        }
    }

    /// The dialect: the flag if given; else g2o for `EDGE_SE2` tags and toro-info for
    /// `EDGE2`/`EDGE` tags, except that TORO-tagged files whose information matrices are all
    /// positive definite in g2o order but not all in TORO order are read in g2o order, with a
    /// warning (GTSAM's w20000.txt is such a file, FORMATS.md §8). Files without edges take their
    /// format's dialect.
    fn decide_dialect(&self, format: Format, warnings: &mut Vec<Warning>) -> (Dialect, String) {
        if let Some(d) = self.options.dialect {
            return (d, "flag".into());
        }
        let Some((family, _, tag)) = &self.first_edge_tag else {
            return (format.default_dialect(), format!("{format} format"));
        };
        match family {
            Family::G2o => (Dialect::G2o, format!("{tag} tags")),
            Family::Toro => {
                let pd = |d| {
                    self.edges
                        .iter()
                        .position(|e| noise_matrix(e.values, d).check_positive_definite().is_err())
                };
                match (pd(Dialect::ToroInfo), pd(Dialect::G2o)) {
                    (Some(bad), None) => {
                        let line = self.sites[bad].line;
                        warnings.push(self.warning(
                            line,
                            format!(
                                "{tag} lines hold information in g2o order (I11 I12 I13 I22 I23 I33): in TORO order this matrix is not positive definite, in g2o order every edge's is; reading the file in dialect g2o (pass --dialect toro-info to insist on TORO order)"
                            ),
                        ));
                        (
                            Dialect::G2o,
                            format!("{tag} tags, values positive definite only in g2o order"),
                        )
                    }
                    _ => (Dialect::ToroInfo, format!("{tag} tags")),
                }
            }
        }
    }

    fn check_positive_definite(&self, edges: &[Edge], dialect: Dialect) -> Result<(), ParseError> {
        for ((e, raw), site) in edges.iter().zip(&self.edges).zip(&self.sites) {
            if let Err(pivot) = e.noise.check_positive_definite() {
                let what = match dialect.noise() {
                    crate::graph::NoiseKind::Information => "information",
                    crate::graph::NoiseKind::Covariance => "covariance",
                };
                let other_order = if dialect.toro_order() {
                    Dialect::G2o
                } else {
                    Dialect::ToroInfo
                };
                let hint = if noise_matrix(raw.values, other_order)
                    .check_positive_definite()
                    .is_ok()
                {
                    if dialect.toro_order() {
                        " (it is in g2o order: try --dialect g2o)"
                    } else {
                        " (it is in TORO order: try --dialect toro-info)"
                    }
                } else {
                    ""
                };
                return Err(self.error(
                    site.line,
                    site.col_noise,
                    ParseErrorKind::NotPositiveDefinite {
                        what,
                        pivot,
                        dialect: dialect.name(),
                        hint,
                    },
                ));
            }
        }
        Ok(())
    }

    /// Poses sorted by id, from the vertex lines, or the ids the edges mention (with identity
    /// poses, to be composed along a spanning tree) when the file has no vertex lines.
    fn vertex_table(&self) -> Result<(Vec<VertexId>, Vec<Pose2>), ParseError> {
        if self.vertices.is_empty() {
            let mut ids: Vec<VertexId> = self.edges.iter().flat_map(|e| [e.i, e.j]).collect();
            ids.sort_unstable();
            ids.dedup();
            let poses = vec![Pose2::IDENTITY; ids.len()];
            return Ok((ids, poses));
        }
        let mut order: Vec<usize> = (0..self.vertices.len()).collect();
        order.sort_by_key(|&k| (self.vertices[k].id, self.vertices[k].line));
        // The duplicate declared earliest in the file is reported.
        let duplicate = order
            .windows(2)
            .filter(|w| self.vertices[w[0]].id == self.vertices[w[1]].id)
            .min_by_key(|w| self.vertices[w[1]].line);
        if let Some(w) = duplicate {
            let (first, second) = (&self.vertices[w[0]], &self.vertices[w[1]]);
            return Err(self.error(
                second.line,
                second.col,
                ParseErrorKind::DuplicateVertex {
                    id: second.id,
                    first_line: first.line,
                },
            ));
        }
        Ok(order
            .iter()
            .map(|&k| (self.vertices[k].id, self.vertices[k].pose))
            .unzip())
    }
}

/// Empties a vector of fields and hands its allocation to a vector of another lifetime (the
/// collect of an empty `into_iter().map()` reuses the buffer in place), so the hot loop does not
/// allocate per line.
fn recycle<'b>(mut v: Vec<Field<'_>>) -> Vec<Field<'b>> {
    v.clear();
    v.into_iter().map(|_| unreachable!()).collect()
}

fn noise_matrix(values: [f64; 6], dialect: Dialect) -> SymMat3 {
    if dialect.toro_order() {
        SymMat3::from_toro(values)
    } else {
        SymMat3(values)
    }
}

fn plural(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// File id -> dense index: a table when ids are dense enough, else a hash map.
enum IdIndex {
    Table(Vec<u32>),
    Map(HashMap<VertexId, usize>),
}

impl IdIndex {
    fn new(ids: &[VertexId]) -> Self {
        let max = ids.last().map_or(0, |&m| m as usize);
        if max <= 4 * ids.len() + 1024 {
            let mut t = vec![u32::MAX; max + 1];
            for (k, &id) in ids.iter().enumerate() {
                t[id as usize] = k as u32;
            }
            IdIndex::Table(t)
        } else {
            IdIndex::Map(ids.iter().enumerate().map(|(k, &id)| (id, k)).collect())
        }
    }

    fn get(&self, id: VertexId) -> Option<usize> {
        match self {
            IdIndex::Table(t) => t
                .get(id as usize)
                .filter(|&&k| k != u32::MAX)
                .map(|&k| k as usize),
            IdIndex::Map(m) => m.get(&id).copied(),
        }
    }
}
