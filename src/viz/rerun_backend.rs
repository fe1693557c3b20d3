//! The rerun backend (cargo feature `rerun`).

use super::{Entity, Item, Target, VIEWER_TIMEOUT_SECONDS, When};
use crate::error::Error;
use rerun::external::re_uri::ProxyUri;
use rerun::sink::{BinaryStreamSink, BinaryStreamStorage, GrpcSink, LogSink};
use rerun::{RecordingStream, RecordingStreamBuilder};
use std::cell::{Cell, RefCell};
use std::collections::BTreeSet;
use std::rc::Rc;
use std::time::Duration;

/// A recording in progress.
pub struct Inner {
    tool: String,
    sink: Sink,
    /// The `.rrd` file: its path, the temporary file it is written to, the encoder's buffer.
    save: Option<(String, tempfile::NamedTempFile, BinaryStreamStorage)>,
    /// URLs of the viewers streamed to.
    viewers: Vec<String>,
    /// The temporary `.rrd` file, listed for removal if the tool is interrupted.
    _listed: Option<crate::io::Pending>,
}

/// Logs entities; cheap to clone (for [`super::Recorder::observe`]).
#[derive(Clone)]
pub struct Sink {
    rec: RecordingStream,
    /// The first logging error: the recording is then incomplete.
    error: Rc<RefCell<Option<String>>>,
    /// Entity paths logged (for the blueprint).
    paths: Rc<RefCell<BTreeSet<String>>>,
    /// Whether 3D entities were logged (a 3D graph): the blueprint's views are then 3D.
    spatial3: Rc<Cell<bool>>,
}

fn invalid(message: String) -> Error {
    Error::Invalid(message)
}

impl Inner {
    pub fn start(tool: &'static str, target: &Target) -> crate::Result<Option<Inner>> {
        // Check everything that can be an error before starting anything.
        let connect = match &target.connect {
            Some(url) => Some(url.parse::<ProxyUri>().map_err(|e| {
                invalid(format!(
                    "--rerun-connect={url}: not the address of a rerun viewer ({e}); expected e.g. {}",
                    super::DEFAULT_CONNECT_URL
                ))
            })?),
            None => None,
        };
        let file = match &target.save {
            Some(path) => {
                let target_path = std::path::Path::new(path);
                let dir = match target_path.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => std::path::Path::new("."),
                };
                let tmp = tempfile::Builder::new()
                    .prefix(".pgo-")
                    .suffix(".rrd.tmp")
                    .tempfile_in(dir)
                    .map_err(|e| {
                        // The OS's reason, without the temporary file's name.
                        let e = e
                            .raw_os_error()
                            .map_or(e, std::io::Error::from_raw_os_error);
                        invalid(format!("--rerun-save {path}: {e}"))
                    })?;
                Some((path.clone(), tmp))
            }
            None => None,
        };
        let rec = RecordingStreamBuilder::new(tool)
            .enabled(true)
            .buffered()
            .map_err(|e| invalid(format!("cannot start the rerun recording: {e}")))?;

        let mut sinks: Vec<Box<dyn LogSink>> = Vec::new();
        let listed = file
            .as_ref()
            .map(|(_, tmp)| crate::io::Pending::list(tmp.path()));
        let save = file.map(|(path, tmp)| {
            let (sink, storage) = BinaryStreamSink::new(rec.clone());
            sinks.push(Box::new(sink));
            (path, tmp, storage)
        });
        let mut viewers: Vec<(String, ProxyUri)> = Vec::new();
        if target.spawn {
            match spawn_viewer() {
                Ok(()) => {
                    let url = super::DEFAULT_CONNECT_URL.to_string();
                    if let Ok(uri) = url.parse::<ProxyUri>() {
                        viewers.push((url, uri));
                    }
                }
                Err(e) => eprintln!("{tool}: warning: cannot start the rerun viewer: {e}"),
            }
        }
        if let (Some(uri), Some(url)) = (connect, &target.connect)
            && !viewers.iter().any(|(_, u)| *u == uri)
        {
            viewers.push((url.clone(), uri));
        }
        for (_, uri) in &viewers {
            sinks.push(Box::new(GrpcSink::new(uri.clone())));
        }
        if sinks.is_empty() {
            return Ok(None);
        }
        rec.set_sinks(sinks);
        Ok(Some(Inner {
            tool: tool.to_string(),
            sink: Sink {
                rec,
                error: Rc::default(),
                paths: Rc::default(),
                spatial3: Rc::default(),
            },
            save,
            viewers: viewers.into_iter().map(|(url, _)| url).collect(),
            _listed: listed,
        }))
    }

    pub fn emit(&self, entity: &Entity) {
        self.sink.emit(entity);
    }

    /// Logs the iterations reported to it at the next steps of the `iteration` timeline.
    pub fn observer(&self, next_step: Rc<Cell<u64>>) -> crate::progress::Observer {
        let sink = self.sink.clone();
        Box::new(move |_solver_step, values| {
            let step = next_step.get();
            next_step.set(step + 1);
            for entity in super::iteration_entities(step, values) {
                sink.emit(&entity);
            }
        })
    }

    pub fn finish(self) -> crate::Result<()> {
        let Inner {
            tool,
            sink,
            save,
            viewers,
            _listed,
        } = self;
        if let Err(e) = blueprint(&sink.paths.borrow(), sink.spatial3.get()).send(
            &sink.rec,
            rerun::blueprint::BlueprintActivation {
                make_active: true,
                make_default: true,
            },
        ) {
            sink.note_error(format!("blueprint: {e}"));
        }
        let flushed = sink
            .rec
            .flush_with_timeout(Duration::from_secs(VIEWER_TIMEOUT_SECONDS));
        if let Err(e) = &flushed
            && !viewers.is_empty()
        {
            eprintln!(
                "{tool}: warning: the rerun viewer at {} did not take the recording: {}",
                viewers.join(", "),
                first_line(&e.to_string())
            );
        }
        let error = sink.error.borrow().clone();
        let mut leftovers = None;
        let result = match save {
            None => Ok(()),
            Some((path, tmp, storage)) => {
                let why = if let Some(e) = error {
                    Some(e)
                } else if let (Err(e), true) = (&flushed, viewers.is_empty()) {
                    Some(e.to_string())
                } else {
                    None
                };
                let result = match (why, storage.read()) {
                    (Some(why), _) => Err(invalid(format!(
                        "cannot save the rerun recording to {path}: {why}"
                    ))),
                    (None, None) => Err(invalid(format!(
                        "cannot save the rerun recording to {path}: it could not be encoded"
                    ))),
                    (None, Some(bytes)) => write_file(&path, tmp, &bytes),
                };
                leftovers = Some(storage);
                result
            }
        };
        if flushed.is_ok() || viewers.is_empty() {
            // Closes the connections to the viewers cleanly (they keep the data only then).
            drop(leftovers);
            drop(sink);
        } else {
            // Dropping the stream would wait for the viewers without limit: they had their
            // chance above, and the process ends now.
            std::mem::forget(leftovers);
            std::mem::forget(sink);
        }
        result
    }
}

/// Starts the `rerun` executable on `PATH` as a viewer listening at the default port,
/// unless something listens there already (a viewer: the recording goes to it). Unlike
/// `rerun::spawn`, the viewer gets no stdin, stdout or stderr of ours, so that it neither
/// writes into the tool's outputs nor holds a pipe open after the tool ends; it runs in its
/// own process group, so that Ctrl-C on the tool leaves it open.
fn spawn_viewer() -> Result<(), String> {
    use std::net::{Ipv4Addr, SocketAddr, TcpStream};
    use std::process::{Command, Stdio};
    let port = rerun::DEFAULT_SERVER_PORT;
    let address = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
    if TcpStream::connect_timeout(&address, Duration::from_millis(200)).is_ok() {
        return Ok(());
    }
    let mut command = Command::new("rerun");
    command
        .arg(format!("--port={port}"))
        .arg("--expect-data-soon")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        command.process_group(0);
    }
    match command.spawn() {
        Ok(_child) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Err("no `rerun` executable on PATH (pip install rerun-sdk==0.36.3 provides it)".into())
        }
        Err(e) => Err(format!("rerun: {e}")),
    }
}

fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or("")
}

/// Writes `bytes` to the temporary file and renames it to `path` (mode 0644 on Unix).
fn write_file(path: &str, tmp: tempfile::NamedTempFile, bytes: &[u8]) -> crate::Result<()> {
    use std::io::Write;
    let fail =
        |e: std::io::Error| invalid(format!("cannot save the rerun recording to {path}: {e}"));
    let mut file = tmp.as_file();
    file.write_all(bytes)
        .and_then(|_| file.flush())
        .map_err(fail)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o644))
            .map_err(fail)?;
    }
    tmp.persist(path).map_err(|e| fail(e.error))?;
    Ok(())
}

/// The viewer layout: the spatial views of what was logged on top (input, optimized,
/// residuals; 2D, or 3D for a 3D graph), the solver's iterations, the spectra and the reports
/// below.
fn blueprint(paths: &BTreeSet<String>, spatial3: bool) -> rerun::blueprint::Blueprint {
    use rerun::blueprint::{
        BarChartView, Blueprint, BlueprintPanel, ContainerLike, Grid, Horizontal, SelectionPanel,
        Spatial2DView, Spatial3DView, TextLogView, TimePanel, TimeSeriesView, Vertical,
    };
    let has = |prefix: &str| paths.iter().any(|p| p.starts_with(prefix));
    // A spatial view: 3D when the graph is.
    let view = |name: &str, origin: &str, contents: Option<&[&str]>| -> ContainerLike {
        if spatial3 {
            let v = Spatial3DView::new(name).with_origin(origin);
            match contents {
                Some(c) => v.with_contents(c.iter().copied()).into(),
                None => v.into(),
            }
        } else {
            let v = Spatial2DView::new(name).with_origin(origin);
            match contents {
                Some(c) => v.with_contents(c.iter().copied()).into(),
                None => v.into(),
            }
        }
    };
    let mut top: Vec<ContainerLike> = Vec::new();
    if has("graph/") {
        top.push(view("graph as read", "/graph", None));
    }
    if has("optimized/") {
        top.push(view(
            "optimized",
            "/optimized",
            Some(&["+ $origin/**", "- /optimized/residuals"]),
        ));
        top.push(view(
            "residuals (cost terms, log scale)",
            "/optimized",
            Some(&["+ /optimized/residuals"]),
        ));
    }
    if has("robust/") {
        top.push(
            Spatial2DView::new("GNC weights (red 0, blue 1) per gnc_iteration")
                .with_origin("/robust")
                .into(),
        );
    }
    let mut bottom: Vec<ContainerLike> = Vec::new();
    // One plot per solver value: each gets its own scale.
    let series: Vec<ContainerLike> = paths
        .iter()
        .filter_map(|p| p.strip_prefix("solver/"))
        .map(|name| {
            TimeSeriesView::new(name)
                .with_origin(format!("/solver/{name}"))
                .into()
        })
        .collect();
    if !series.is_empty() {
        bottom.push(Grid::new(series).with_name("solver iterations").into());
    }
    for (path, name) in [
        ("spectrum/eigenvalues", "eigenvalues of W"),
        (
            "spectrum/penalized_eigenvalues",
            "eigenvalues of W(lambda*)",
        ),
        ("spectrum/rotation_eigenvalues", "eigenvalues of M"),
    ] {
        if paths.contains(path) {
            bottom.push(
                BarChartView::new(name)
                    .with_origin(format!("/{path}"))
                    .into(),
            );
        }
    }
    if has("report/") {
        bottom.push(TextLogView::new("report").with_origin("/report").into());
    }
    let rows: Vec<ContainerLike> = [top, bottom]
        .into_iter()
        .filter(|row| !row.is_empty())
        .map(|row| Horizontal::new(row).into())
        .collect();
    let shares = if rows.len() == 2 {
        vec![3.0, 1.0]
    } else {
        vec![1.0]
    };
    // The views get the room: the side panels start collapsed (a click opens them).
    let collapsed = rerun::blueprint::components::PanelState::Collapsed;
    Blueprint::new(Vertical::new(rows).with_row_shares(shares))
        .with_blueprint_panel(BlueprintPanel::from_state(collapsed))
        .with_selection_panel(SelectionPanel::from_state(collapsed))
        .with_time_panel(TimePanel::new().with_state(collapsed))
}

fn rgb([r, g, b]: [u8; 3]) -> rerun::Color {
    rerun::Color::from_rgb(r, g, b)
}

impl Sink {
    fn note_error(&self, message: String) {
        let mut slot = self.error.borrow_mut();
        if slot.is_none() {
            *slot = Some(message);
        }
    }

    pub fn emit(&self, entity: &Entity) {
        let rec = &self.rec;
        rec.reset_time();
        let is_static = match entity.when {
            When::Static => true,
            When::Iteration(step) => {
                rec.set_time_sequence("iteration", i64::try_from(step).unwrap_or(i64::MAX));
                false
            }
            When::GncIteration(step) => {
                rec.set_time_sequence("gnc_iteration", i64::try_from(step).unwrap_or(i64::MAX));
                false
            }
        };
        let path = entity.path.as_str();
        if matches!(
            entity.item,
            Item::Points3 { .. } | Item::Arrows3 { .. } | Item::Strips3 { .. }
        ) {
            self.spatial3.set(true);
        }
        let result = match &entity.item {
            Item::Points {
                positions,
                color,
                radius,
            } => self.log(
                path,
                is_static,
                &rerun::Points2D::new(positions.iter().copied())
                    .with_colors([rgb(*color)])
                    .with_radii([rerun::Radius::new_ui_points(*radius)]),
            ),
            Item::Arrows {
                origins,
                vectors,
                color,
                radius,
            } => self.log(
                path,
                is_static,
                &rerun::Arrows2D::from_vectors(vectors.iter().copied())
                    .with_origins(origins.iter().copied())
                    .with_colors([rgb(*color)])
                    .with_radii([rerun::Radius::new_ui_points(*radius)]),
            ),
            Item::Strips {
                strips,
                colors,
                radius,
            } => self.log(
                path,
                is_static,
                &rerun::LineStrips2D::new(strips.iter().copied())
                    .with_colors(colors.iter().map(|c| rgb(*c)))
                    .with_radii([rerun::Radius::new_ui_points(*radius)]),
            ),
            Item::Points3 {
                positions,
                color,
                radius,
            } => self.log(
                path,
                is_static,
                &rerun::Points3D::new(positions.iter().copied())
                    .with_colors([rgb(*color)])
                    .with_radii([rerun::Radius::new_ui_points(*radius)]),
            ),
            Item::Arrows3 {
                origins,
                vectors,
                color,
                radius,
            } => self.log(
                path,
                is_static,
                &rerun::Arrows3D::from_vectors(vectors.iter().copied())
                    .with_origins(origins.iter().copied())
                    .with_colors([rgb(*color)])
                    .with_radii([rerun::Radius::new_ui_points(*radius)]),
            ),
            Item::Strips3 {
                strips,
                colors,
                radius,
            } => self.log(
                path,
                is_static,
                &rerun::LineStrips3D::new(strips.iter().copied())
                    .with_colors(colors.iter().map(|c| rgb(*c)))
                    .with_radii([rerun::Radius::new_ui_points(*radius)]),
            ),
            Item::Bars(values) => self.log(path, is_static, &rerun::BarChart::new(values.clone())),
            Item::Scalar(value) => self.log(path, is_static, &rerun::Scalars::new([*value])),
            Item::Text { text, warning } => self.log(
                path,
                is_static,
                &rerun::TextLog::new(text.as_str()).with_level(if *warning {
                    rerun::TextLogLevel::WARN
                } else {
                    rerun::TextLogLevel::INFO
                }),
            ),
        };
        let result = result.and_then(|()| {
            if entity.values.is_empty() {
                return Ok(());
            }
            let mut any = rerun::AnyValues::default();
            for (name, values) in &entity.values {
                any = any.with_component::<rerun::components::Scalar>(*name, values.clone());
            }
            self.log(path, is_static, &any)
        });
        if let Err(e) = result {
            self.note_error(format!("{path}: {e}"));
        }
        self.paths.borrow_mut().insert(entity.path.clone());
    }

    fn log(
        &self,
        path: &str,
        is_static: bool,
        archetype: &impl rerun::AsComponents,
    ) -> rerun::RecordingStreamResult<()> {
        if is_static {
            self.rec.log_static(path, archetype)
        } else {
            self.rec.log(path, archetype)
        }
    }
}
