//! Parsing the lines of a block of the input: both formats' pose tags are recognized (as GTSAM
//! does), well-formed vertex and edge lines take a one-pass fast path, everything else the
//! general path that also reports what is wrong, with its line and column.

use super::lexer::{
    Field, parse_f64, parse_id, scan_f64, scan_f64s, scan_id, skip_space, split_fields,
};
use super::options::ReadOptions;
use super::{g2o, toro};
use crate::error::{Location, ParseError, ParseErrorKind};
use crate::graph::{Edge, LandmarkForm, Pose2, SymMat2, SymMat3, VertexId};
use crate::vertigo::{self, EdgeKind, SwitchPrior, SwitchVertex};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Family {
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
    LandmarkVertex(LandmarkForm),
    Observation(LandmarkForm),
    Prior,
    /// Vertigo's `EDGE_SE2_SWITCHABLE` (true) or `EDGE_SE2_MAXMIX` (false).
    RobustEdge(bool),
    SwitchVertex,
    SwitchPrior,
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
    } else if tag == g2o::LANDMARK_EDGE.as_bytes() {
        Tag::Observation(LandmarkForm::G2o)
    } else if tag == g2o::LANDMARK2.as_bytes() {
        Tag::Observation(LandmarkForm::Landmark2)
    } else if tag == g2o::LANDMARK_VERTEX.as_bytes() {
        Tag::LandmarkVertex(LandmarkForm::G2o)
    } else if tag == g2o::POINT2.as_bytes() {
        Tag::LandmarkVertex(LandmarkForm::Landmark2)
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
    } else if tag == vertigo::EDGE_SWITCHABLE.as_bytes() {
        Tag::RobustEdge(true)
    } else if tag == vertigo::EDGE_MAXMIX.as_bytes() {
        Tag::RobustEdge(false)
    } else if tag == vertigo::VERTEX_SWITCH.as_bytes() {
        Tag::SwitchVertex
    } else if tag == vertigo::EDGE_SWITCH_PRIOR.as_bytes() {
        Tag::SwitchPrior
    } else {
        Tag::Unknown
    }
}

/// A vertex line as read (32 bytes: positions are 32-bit like [`EdgeSite`]'s, as the table
/// of raw vertices is the largest the reader holds besides the graph).
pub(super) struct RawVertex {
    pub(super) id: VertexId,
    pub(super) line: u32,
    pub(super) col: u32,
    pub(super) pose: Pose2,
}

/// Where an edge line's fields are, for messages after the whole file is read (32-bit to keep
/// the per-edge memory small; positions beyond 2^32 - 1 are shown as 4294967295).
pub(super) struct EdgeSite {
    pub(super) line: u32,
    pub(super) col_i: u32,
    pub(super) col_j: u32,
    pub(super) col_noise: u32,
}

fn narrow(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// A landmark vertex line as read (`VERTEX_XY` or `POINT2`).
pub(super) struct RawLandmark {
    pub(super) id: VertexId,
    pub(super) line: u32,
    pub(super) col: u32,
    pub(super) position: [f64; 2],
}

/// A landmark observation line as read (`EDGE_SE2_XY` or `LANDMARK2`): file ids, values in
/// file order, and where its fields are.
pub(super) struct RawObservation {
    pub(super) pose: VertexId,
    pub(super) landmark: VertexId,
    pub(super) d: [f64; 2],
    pub(super) information: SymMat2,
    pub(super) site: EdgeSite,
}

/// Where the first line of a landmark form is (its tag's line and column, and spelling).
#[derive(Debug, Clone)]
pub(super) struct FormTag {
    pub(super) line: usize,
    pub(super) col: usize,
    pub(super) tag: String,
}

pub(super) struct Skipped {
    pub(super) first_line: usize,
    pub(super) count: usize,
}

/// Where an edge tag first appears.
#[derive(Debug, Clone)]
pub(super) struct EdgeTag {
    pub(super) family: Family,
    pub(super) line: usize,
    pub(super) col: usize,
    pub(super) tag: String,
}

/// What a run of consecutive lines holds, before ids are resolved.
#[derive(Default)]
pub(super) struct Block {
    pub(super) vertices: Vec<RawVertex>,
    /// Edges as read: `i` and `j` hold the file's ids, `noise` the six values in file order
    /// (both are resolved in [`Reader::finish`], in place).
    pub(super) edges: Vec<Edge>,
    pub(super) sites: Vec<EdgeSite>,
    pub(super) fixed: Vec<(VertexId, usize, usize)>,
    /// The first edge tag: its family, line and spelling.
    pub(super) first_edge_tag: Option<EdgeTag>,
    pub(super) first_vertex_family: Option<Family>,
    pub(super) unknown: Vec<(String, Skipped)>,
    pub(super) equiv: Option<Skipped>,
    pub(super) landmarks: Vec<RawLandmark>,
    pub(super) observations: Vec<RawObservation>,
    /// The first landmark line of each form: g2o's (`VERTEX_XY`, `EDGE_SE2_XY`) and CPL-SLAM's
    /// (`LANDMARK2`, `POINT2`).
    pub(super) first_g2o_landmark: Option<FormTag>,
    pub(super) first_landmark2: Option<FormTag>,
    /// Vertigo's edges: (position in `edges`, kind), and the line of the first Vertigo line.
    pub(super) kinds: Vec<(usize, EdgeKind)>,
    pub(super) switches: Vec<SwitchVertex>,
    pub(super) priors: Vec<SwitchPrior>,
    pub(super) first_vertigo_line: Option<usize>,
}

/// Parses the lines of one block.
struct BlockParser<'a> {
    name: &'a str,
    options: &'a ReadOptions,
    block: Block,
    /// The file's first edge tag, when known: later edge tags of the other format are an error.
    reference: Option<EdgeTag>,
}

/// Parses `bytes`, complete lines whose first is line `first_line` of the file, reserving room
/// for at least `capacity` vertices and edges.
pub(super) fn parse_block(
    name: &str,
    options: &ReadOptions,
    bytes: &[u8],
    first_line: usize,
    reference: Option<EdgeTag>,
    capacity: usize,
) -> Result<Block, ParseError> {
    // Every line holds at most one vertex or edge: reserving for all of them avoids regrowing
    // (pages that are reserved but never written cost nothing).
    let capacity = capacity.max(memchr::memchr_iter(b'\n', bytes).count() + 1);
    let mut block = Block::default();
    block.edges.reserve(capacity);
    block.sites.reserve(capacity);
    block.vertices.reserve(capacity);
    let mut p = BlockParser {
        name,
        options,
        block,
        reference,
    };
    // Field storage reused across lines (see `recycle`).
    let mut spare: Vec<Field<'static>> = Vec::with_capacity(16);
    let mut line_no = first_line;
    let mut pos = 0;
    while pos < bytes.len() {
        let end = memchr::memchr(b'\n', &bytes[pos..]).map_or(bytes.len(), |k| pos + k);
        let mut line = &bytes[pos..end];
        if line_no == 1 {
            line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
        }
        if !p.fast_line(line_no, line) {
            let mut fields = recycle(std::mem::take(&mut spare));
            split_fields(line, &mut fields);
            p.line(line_no, line, &fields)?;
            spare = recycle(fields);
        }
        pos = end + 1;
        line_no += 1;
    }
    Ok(p.block)
}

pub(super) fn mixed_tags(first: &EdgeTag, tag: &str) -> ParseErrorKind {
    ParseErrorKind::MixedTags {
        first: first.tag.clone(),
        first_line: first.line,
        tag: tag.to_string(),
    }
}

pub(super) fn make_error(name: &str, line: usize, col: usize, kind: ParseErrorKind) -> ParseError {
    ParseError {
        location: Location {
            path: name.to_string(),
            line,
            col,
        },
        kind,
    }
}

impl BlockParser<'_> {
    fn error(&self, line: usize, col: usize, kind: ParseErrorKind) -> ParseError {
        make_error(self.name, line, col, kind)
    }

    /// The hot path: a well-formed vertex or edge line in one pass over its bytes. Returns false,
    /// having recorded nothing, for any other line or anything unusual in it (the general path
    /// then reads it, and reports what is wrong).
    fn fast_line(&mut self, line_no: usize, line: &[u8]) -> bool {
        let mut s = line;
        skip_space(&mut s);
        let tag_col = line.len() - s.len() + 1;
        let tag_len = s.iter().take_while(|c| !c.is_ascii_whitespace()).count();
        let (tag, mut s) = s.split_at(tag_len);
        let col = |s: &[u8]| narrow(line.len() - s.len() + 1);
        match classify(tag) {
            Tag::Vertex(family) => {
                let mut v = [0.0; 3];
                skip_space(&mut s);
                let id_col = col(s);
                let Some(id) = scan_id(&mut s) else {
                    return false;
                };
                if !scan_f64s(&mut s, &mut v) {
                    return false;
                }
                skip_space(&mut s);
                if !s.is_empty() {
                    return false;
                }
                self.record_vertex(family, id, v, line_no, id_col as usize);
                true
            }
            Tag::Edge(family) => {
                skip_space(&mut s);
                let col_i = col(s);
                let Some(i) = scan_id(&mut s) else {
                    return false;
                };
                skip_space(&mut s);
                let col_j = col(s);
                let Some(j) = scan_id(&mut s) else {
                    return false;
                };
                let mut v = [0.0; 9];
                let mut col_noise = 0;
                for (k, x) in v.iter_mut().enumerate() {
                    skip_space(&mut s);
                    if k == 3 {
                        col_noise = col(s);
                    }
                    match scan_f64(&mut s) {
                        Some(value) => *x = value,
                        None => return false,
                    }
                }
                skip_space(&mut s);
                let site = EdgeSite {
                    line: narrow(line_no),
                    col_i,
                    col_j,
                    col_noise,
                };
                s.is_empty()
                    && self
                        .record_edge(family, tag, tag_col, i, j, v, site)
                        .is_ok()
            }
            _ => false,
        }
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
            Tag::Fix => self.fix(line_no, fields),
            Tag::Equiv => {
                if self.options.strict || !self.options.ignore_equiv {
                    return Err(at_tag(ParseErrorKind::Equiv));
                }
                let e = self.block.equiv.get_or_insert(Skipped {
                    first_line: line_no,
                    count: 0,
                });
                e.count += 1;
                Ok(())
            }
            Tag::ThreeD => Err(at_tag(ParseErrorKind::ThreeD { tag: tag_name() })),
            Tag::Landmark => Err(at_tag(ParseErrorKind::Landmark { tag: tag_name() })),
            Tag::LandmarkVertex(form) => self.landmark_vertex(line_no, line, fields, form),
            Tag::Observation(form) => self.observation(line_no, line, fields, form),
            Tag::Prior => Err(at_tag(ParseErrorKind::Prior { tag: tag_name() })),
            Tag::RobustEdge(switchable) => self.robust_edge(line_no, line, fields, switchable),
            Tag::SwitchVertex => {
                let a = self.expect_fields(line_no, line, fields, 2, "id value")?;
                let v = SwitchVertex {
                    id: self.id(line_no, &a[0])?,
                    value: self.num(line_no, &a[1])?,
                };
                self.block.switches.push(v);
                self.block.first_vertigo_line.get_or_insert(line_no);
                Ok(())
            }
            Tag::SwitchPrior => {
                let a = self.expect_fields(line_no, line, fields, 3, "id prior information")?;
                let p = SwitchPrior {
                    id: self.id(line_no, &a[0])?,
                    prior: self.num(line_no, &a[1])?,
                    information: self.num(line_no, &a[2])?,
                };
                self.block.priors.push(p);
                self.block.first_vertigo_line.get_or_insert(line_no);
                Ok(())
            }
            Tag::Unknown => {
                let name = tag_name();
                if self.options.strict {
                    return Err(at_tag(ParseErrorKind::UnknownTag { tag: name }));
                }
                match self.block.unknown.iter_mut().find(|(t, _)| *t == name) {
                    Some((_, s)) => s.count += 1,
                    None => self.block.unknown.push((
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
        let mut v = [0.0; 3];
        for (x, f) in v.iter_mut().zip(&a[1..]) {
            *x = self.num(line_no, f)?;
        }
        self.record_vertex(family, id, v, line_no, a[0].col);
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
        let mut v = [0.0; 9];
        for (x, f) in v.iter_mut().zip(&a[2..]) {
            *x = self.num(line_no, f)?;
        }
        let site = EdgeSite {
            line: narrow(line_no),
            col_i: narrow(a[0].col),
            col_j: narrow(a[1].col),
            col_noise: narrow(a[5].col),
        };
        let tag = &fields[0];
        self.record_edge(family, tag.text, tag.col, i, j, v, site)
    }

    /// `EDGE_SE2_SWITCHABLE i j s ...` or `EDGE_SE2_MAXMIX i j w ...`: an `EDGE_SE2` with one
    /// more field after the ids.
    fn robust_edge(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        switchable: bool,
    ) -> Result<(), ParseError> {
        let layout = if switchable {
            "i j switch_id dx dy dtheta and 6 information values I11 I12 I13 I22 I23 I33"
        } else {
            "i j weight dx dy dtheta and 6 information values I11 I12 I13 I22 I23 I33"
        };
        let a = self.expect_fields(line_no, line, fields, 12, layout)?;
        let i = self.id(line_no, &a[0])?;
        let j = self.id(line_no, &a[1])?;
        let kind = if switchable {
            EdgeKind::Switchable {
                switch: self.id(line_no, &a[2])?,
            }
        } else {
            EdgeKind::MaxMix {
                weight: self.num(line_no, &a[2])?,
            }
        };
        let mut v = [0.0; 9];
        for (x, f) in v.iter_mut().zip(&a[3..]) {
            *x = self.num(line_no, f)?;
        }
        let site = EdgeSite {
            line: narrow(line_no),
            col_i: narrow(a[0].col),
            col_j: narrow(a[1].col),
            col_noise: narrow(a[6].col),
        };
        let tag = &fields[0];
        self.record_edge(Family::G2o, tag.text, tag.col, i, j, v, site)?;
        self.block.kinds.push((self.block.edges.len() - 1, kind));
        self.block.first_vertigo_line.get_or_insert(line_no);
        Ok(())
    }

    #[inline(always)]
    fn record_vertex(
        &mut self,
        family: Family,
        id: VertexId,
        v: [f64; 3],
        line: usize,
        col: usize,
    ) {
        self.block.first_vertex_family.get_or_insert(family);
        self.block.vertices.push(RawVertex {
            id,
            pose: Pose2::new(v[0], v[1], v[2]),
            line: narrow(line),
            col: narrow(col),
        });
    }

    /// Records an edge `i j dx dy dθ` + six noise values (`v`), after checking it is no
    /// self-loop and that its tag is of the same format as the file's first edge tag (unless a
    /// dialect was given); on error nothing is recorded.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn record_edge(
        &mut self,
        family: Family,
        tag: &[u8],
        tag_col: usize,
        i: VertexId,
        j: VertexId,
        v: [f64; 9],
        site: EdgeSite,
    ) -> Result<(), ParseError> {
        let line = site.line as usize;
        if i == j {
            let kind = ParseErrorKind::SelfLoop { id: i };
            return Err(self.error(line, site.col_j as usize, kind));
        }
        let here = || EdgeTag {
            family,
            line,
            col: tag_col,
            tag: String::from_utf8_lossy(tag).into_owned(),
        };
        match &self.reference {
            None => self.reference = Some(here()),
            Some(first) if first.family != family && self.options.dialect.is_none() => {
                let kind = mixed_tags(first, &String::from_utf8_lossy(tag));
                return Err(self.error(line, tag_col, kind));
            }
            Some(_) => {}
        }
        if self.block.first_edge_tag.is_none() {
            self.block.first_edge_tag = Some(here());
        }
        self.block.edges.push(Edge {
            i: i as usize,
            j: j as usize,
            measurement: Pose2::new(v[0], v[1], v[2]),
            noise: SymMat3([v[3], v[4], v[5], v[6], v[7], v[8]]),
        });
        self.block.sites.push(site);
        Ok(())
    }

    fn note_form(&mut self, form: LandmarkForm, line_no: usize, tag: &Field) {
        let slot = match form {
            LandmarkForm::G2o => &mut self.block.first_g2o_landmark,
            LandmarkForm::Landmark2 => &mut self.block.first_landmark2,
        };
        slot.get_or_insert_with(|| FormTag {
            line: line_no,
            col: tag.col,
            tag: tag.lossy(),
        });
    }

    fn landmark_vertex(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        form: LandmarkForm,
    ) -> Result<(), ParseError> {
        let a = self.expect_fields(line_no, line, fields, 3, "id x y")?;
        let id = self.id(line_no, &a[0])?;
        let x = self.num(line_no, &a[1])?;
        let y = self.num(line_no, &a[2])?;
        self.note_form(form, line_no, &fields[0]);
        self.block.landmarks.push(RawLandmark {
            id,
            line: narrow(line_no),
            col: narrow(a[0].col),
            position: [x, y],
        });
        Ok(())
    }

    fn observation(
        &mut self,
        line_no: usize,
        line: &[u8],
        fields: &[Field],
        form: LandmarkForm,
    ) -> Result<(), ParseError> {
        let layout = match form {
            LandmarkForm::G2o => "pose point dx dy I11 I12 I22",
            LandmarkForm::Landmark2 => "pose landmark dx dy I11 I12 I22",
        };
        let a = self.expect_fields(line_no, line, fields, 7, layout)?;
        let pose = self.id(line_no, &a[0])?;
        let landmark = self.id(line_no, &a[1])?;
        let mut v = [0.0; 5];
        for (x, f) in v.iter_mut().zip(&a[2..]) {
            *x = self.num(line_no, f)?;
        }
        if form == LandmarkForm::G2o && pose == landmark {
            let kind = ParseErrorKind::SelfLoop { id: pose };
            return Err(self.error(line_no, a[1].col, kind));
        }
        self.note_form(form, line_no, &fields[0]);
        self.block.observations.push(RawObservation {
            pose,
            landmark,
            d: [v[0], v[1]],
            information: SymMat2([v[2], v[3], v[4]]),
            site: EdgeSite {
                line: narrow(line_no),
                col_i: narrow(a[0].col),
                col_j: narrow(a[1].col),
                col_noise: narrow(a[4].col),
            },
        });
        Ok(())
    }

    fn fix(&mut self, line_no: usize, fields: &[Field]) -> Result<(), ParseError> {
        let args: Vec<&Field> = fields[1..]
            .iter()
            .take_while(|f| f.text.first() != Some(&b'#'))
            .collect();
        if args.is_empty() {
            // Just past the tag: a trailing comment is not where the ids were expected.
            let col = fields[0].col + fields[0].text.len();
            return Err(self.error(line_no, col, ParseErrorKind::NoFixIds));
        }
        for f in args {
            let id = self.id(line_no, f)?;
            self.block.fixed.push((id, line_no, f.col));
        }
        Ok(())
    }
}

/// Empties a vector of fields and hands its allocation to a vector of another lifetime (the
/// collect of an empty `into_iter().map()` reuses the buffer in place), so the hot loop does not
/// allocate per line.
fn recycle<'b>(mut v: Vec<Field<'_>>) -> Vec<Field<'b>> {
    v.clear();
    v.into_iter().map(|_| unreachable!()).collect()
}
