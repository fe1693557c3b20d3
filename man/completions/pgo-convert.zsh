#compdef pgo-convert

autoload -U is-at-least

_pgo-convert() {
    typeset -A opt_args
    typeset -a _arguments_options
    local ret=1

    if is-at-least 5.2; then
        _arguments_options=(-s -S -C)
    else
        _arguments_options=(-s -C)
    fi

    local context curcontext="$curcontext" state line
    _arguments "${_arguments_options[@]}" : \
'(--stats)-o+[Output file, or - for stdout]:OUT:_default' \
'(--stats)--output=[Output file, or - for stdout]:OUT:_default' \
'--from=[Input format \[default\: from the extension (.g2o, .graph), else from the tags\]]:FORMAT:((g2o\:"g2o\: \`VERTEX_SE2\`, \`EDGE_SE2\`, \`FIX\` (docs/formats.md §2)"
toro\:"TORO\: \`VERTEX2\`/\`VERTEX\`, \`EDGE2\`/\`EDGE\` (docs/formats.md §3)"))' \
'(--stats)--to=[Output format \[default\: from the output'\''s extension, else the input format\]; tum and kitti write the poses only, sorted by id, as trajectory files for evo (TUM\: \`t x y z qx qy qz qw\` with t the vertex id or --stamps, z = qx = qy = 0 for a planar graph; KITTI\: the rows of \[R | t\])]:FORMAT:(g2o toro tum kitti)' \
'(--stats)--stamps=[With --to tum\: time stamps of the poses, a file of \`id stamp\` lines \[default\: the vertex id\]]:FILE:_default' \
'--dialect=[How to read the six noise values of each edge \[default\: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags\]]:DIALECT:((g2o\:"Information, g2o order \`I11 I12 I13 I22 I23 I33\` (g2o; GTSAM'\''s readG2o)"
toro-info\:"Information, TORO order \`ff fs ss rr fr sr\` (TORO, HOG-Man)"
toro-cov\:"Covariance, TORO order (GTSAM'\''s \`.graph\` files, read by \`load2D\` as covariances)"
g2o-cov\:"Covariance, g2o order"))' \
'(--stats)--to-dialect=[How to write the noise values \[default\: g2o for g2o output, toro-info for TORO output\]; covariances and information matrices are inverted into each other when the kinds differ]:DIALECT:((g2o\:"Information, g2o order \`I11 I12 I13 I22 I23 I33\` (g2o; GTSAM'\''s readG2o)"
toro-info\:"Information, TORO order \`ff fs ss rr fr sr\` (TORO, HOG-Man)"
toro-cov\:"Covariance, TORO order (GTSAM'\''s \`.graph\` files, read by \`load2D\` as covariances)"
g2o-cov\:"Covariance, g2o order"))' \
'(--stats)--landmarks=[Write landmarks in this form\: g2o (VERTEX_XY, EDGE_SE2_XY; one id space with the poses) or landmark2 (CPL-SLAM'\''s LANDMARK2, landmark ids of their own; positions on POINT2 lines) \[default\: the input'\''s\]. To g2o, landmark id k becomes k + OFFSET\: --landmark-offset, else 0 when no landmark id is a pose id, else the largest pose id + 1 (printed on stderr); to landmark2, k becomes k - OFFSET (default 0), so the same offset converts back]:FORM:((g2o\:"g2o'\''s types\: \`VERTEX_XY id x y\`, \`EDGE_SE2_XY pose point dx dy I11 I12 I22\`; landmark ids share one id space with the poses"
landmark2\:"CPL-SLAM'\''s \`LANDMARK2 pose landmark dx dy I11 I12 I22\` (positions, if any, on \`POINT2 id x y\` lines, which CPL-SLAM skips); landmark ids live in their own id space"))' \
'--landmark-offset=[With --landmarks\: the offset between the two id spaces (see --landmarks)]:OFFSET:_default' \
'--rerun-save=[Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with \`rerun PATH.rrd\`]:PATH.rrd:_default' \
'--rerun-connect=[Stream the recording to a running rerun viewer, at URL if given \[default\: rerun+http\://127.0.0.1\:9876/proxy\]; an unreachable viewer is a warning]::URL:_default' \
'--reindex[Renumber vertices 0..n-1 in ascending order of their ids (landmarks follow as n..n+m in g2o'\''s form, 0..m-1 in the LANDMARK2 form)]' \
'--strict[Treat unknown tags as errors instead of skipping them with a warning]' \
'(--strict)--ignore-equiv[Skip TORO'\''s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file\: the graph written is the file'\''s without them (--stats always skips them with a warning)]' \
'--allow-indefinite[Accept noise matrices that are not positive definite]' \
'--stats[Print statistics (poses, edges, odometry and loop closures, components, ids, duplicates) instead of converting]' \
'--json[With --stats\: one JSON object on stdout]' \
'--timings[Print the time spent reading and writing on stderr]' \
'-q[Do not print the summary line on stderr (warnings are still printed), nor the progress display (shown on stderr only when stderr is a terminal)]' \
'--quiet[Do not print the summary line on stderr (warnings are still printed), nor the progress display (shown on stderr only when stderr is a terminal)]' \
'(-q --quiet)--progress[Show the progress even when stderr is not a terminal, as plain lines (for logs)]' \
'--rerun-spawn[Start a rerun viewer (the \`rerun\` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it]' \
'-h[Print help (see more with '\''--help'\'')]' \
'--help[Print help (see more with '\''--help'\'')]' \
'-V[Print version]' \
'--version[Print version]' \
':input -- Input file, or - for stdin:_default' \
&& ret=0
}

(( $+functions[_pgo-convert_commands] )) ||
_pgo-convert_commands() {
    local commands; commands=()
    _describe -t commands 'pgo-convert commands' commands "$@"
}

if [ "$funcstack[1]" = "_pgo-convert" ]; then
    _pgo-convert "$@"
else
    compdef _pgo-convert pgo-convert
fi
