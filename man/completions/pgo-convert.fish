complete -c pgo-convert -s o -l output -d 'Output file, or - for stdout' -r
complete -c pgo-convert -l from -d 'Input format [default: from the extension (.g2o, .graph), else from the tags]' -r -f -a "g2o\t'g2o: `VERTEX_SE2`, `EDGE_SE2`, `FIX` (docs/formats.md §2)'
toro\t'TORO: `VERTEX2`/`VERTEX`, `EDGE2`/`EDGE` (docs/formats.md §3)'"
complete -c pgo-convert -l to -d 'Output format [default: from the output\'s extension, else the input format]; tum and kitti write the poses only, sorted by id, as trajectory files for evo (TUM: `t x y z qx qy qz qw` with t the vertex id or --stamps, z = qx = qy = 0 for a planar graph; KITTI: the rows of [R | t])' -r -f -a "g2o\t''
toro\t''
tum\t''
kitti\t''"
complete -c pgo-convert -l stamps -d 'With --to tum: time stamps of the poses, a file of `id stamp` lines [default: the vertex id]' -r
complete -c pgo-convert -l dialect -d 'How to read the six noise values of each edge [default: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags]' -r -f -a "g2o\t'Information, g2o order `I11 I12 I13 I22 I23 I33` (g2o; GTSAM\'s readG2o)'
toro-info\t'Information, TORO order `ff fs ss rr fr sr` (TORO, HOG-Man)'
toro-cov\t'Covariance, TORO order (GTSAM\'s `.graph` files, read by `load2D` as covariances)'
g2o-cov\t'Covariance, g2o order'"
complete -c pgo-convert -l to-dialect -d 'How to write the noise values [default: g2o for g2o output, toro-info for TORO output]; covariances and information matrices are inverted into each other when the kinds differ' -r -f -a "g2o\t'Information, g2o order `I11 I12 I13 I22 I23 I33` (g2o; GTSAM\'s readG2o)'
toro-info\t'Information, TORO order `ff fs ss rr fr sr` (TORO, HOG-Man)'
toro-cov\t'Covariance, TORO order (GTSAM\'s `.graph` files, read by `load2D` as covariances)'
g2o-cov\t'Covariance, g2o order'"
complete -c pgo-convert -l landmarks -d 'Write landmarks in this form: g2o (VERTEX_XY, EDGE_SE2_XY; one id space with the poses) or landmark2 (CPL-SLAM\'s LANDMARK2, landmark ids of their own; positions on POINT2 lines) [default: the input\'s]. To g2o, landmark id k becomes k + OFFSET: --landmark-offset, else 0 when no landmark id is a pose id, else the largest pose id + 1 (printed on stderr); to landmark2, k becomes k - OFFSET (default 0), so the same offset converts back' -r -f -a "g2o\t'g2o\'s types: `VERTEX_XY id x y`, `EDGE_SE2_XY pose point dx dy I11 I12 I22`; landmark ids share one id space with the poses'
landmark2\t'CPL-SLAM\'s `LANDMARK2 pose landmark dx dy I11 I12 I22` (positions, if any, on `POINT2 id x y` lines, which CPL-SLAM skips); landmark ids live in their own id space'"
complete -c pgo-convert -l landmark-offset -d 'With --landmarks: the offset between the two id spaces (see --landmarks)' -r
complete -c pgo-convert -l rerun-save -d 'Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with `rerun PATH.rrd`' -r
complete -c pgo-convert -l rerun-connect -d 'Stream the recording to a running rerun viewer, at URL if given [default: rerun+http://127.0.0.1:9876/proxy]; an unreachable viewer is a warning' -r
complete -c pgo-convert -l reindex -d 'Renumber vertices 0..n-1 in ascending order of their ids (landmarks follow as n..n+m in g2o\'s form, 0..m-1 in the LANDMARK2 form)'
complete -c pgo-convert -l strict -d 'Treat unknown tags as errors instead of skipping them with a warning'
complete -c pgo-convert -l ignore-equiv -d 'Skip TORO\'s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file: the graph written is the file\'s without them (--stats always skips them with a warning)'
complete -c pgo-convert -l allow-indefinite -d 'Accept noise matrices that are not positive definite'
complete -c pgo-convert -l stats -d 'Print statistics (poses, edges, odometry and loop closures, components, ids, duplicates) instead of converting'
complete -c pgo-convert -l json -d 'With --stats: one JSON object on stdout'
complete -c pgo-convert -l timings -d 'Print the time spent reading and writing on stderr'
complete -c pgo-convert -s q -l quiet -d 'Do not print the summary line on stderr (warnings are still printed), nor the progress display (shown on stderr only when stderr is a terminal)'
complete -c pgo-convert -l progress -d 'Show the progress even when stderr is not a terminal, as plain lines (for logs)'
complete -c pgo-convert -l rerun-spawn -d 'Start a rerun viewer (the `rerun` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it'
complete -c pgo-convert -s h -l help -d 'Print help (see more with \'--help\')'
complete -c pgo-convert -s V -l version -d 'Print version'
