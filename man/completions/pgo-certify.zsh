#compdef pgo-certify

autoload -U is-at-least

_pgo-certify() {
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
'--from=[Input format \[default\: from the extension (.g2o, .graph), else from the tags\]]:FORMAT:((g2o\:"g2o\: \`VERTEX_SE2\`, \`EDGE_SE2\`, \`FIX\` (docs/formats.md §2)"
toro\:"TORO\: \`VERTEX2\`/\`VERTEX\`, \`EDGE2\`/\`EDGE\` (docs/formats.md §3)"))' \
'--dialect=[How to read the six noise values of each edge \[default\: g2o for EDGE_SE2 tags, toro-info for EDGE2/EDGE tags\]]:DIALECT:((g2o\:"Information, g2o order \`I11 I12 I13 I22 I23 I33\` (g2o; GTSAM'\''s readG2o)"
toro-info\:"Information, TORO order \`ff fs ss rr fr sr\` (TORO, HOG-Man)"
toro-cov\:"Covariance, TORO order (GTSAM'\''s \`.graph\` files, read by \`load2D\` as covariances)"
g2o-cov\:"Covariance, g2o order"))' \
'--estimate=[The estimate\: a g2o or TORO file whose vertex lines hold the poses, by id \[default\: the graph file'\''s own vertices\]]:EST:_default' \
'--weights=[Edge weights\: unit (the paper'\''s cost (5)) or isotropic (tau = 2/tr(inv(Omega_tt)), kappa = 2 Omega_thth\: the SE-Sync/CPL-SLAM objective)]:POLICY:((unit\:"τ = κ = 1\: exactly the paper'\''s cost (5)/(8)"
isotropic\:"τ = 2 / tr(Ω_tt⁻¹), κ = 2 Ω_θθ\: the objective of SE-Sync and CPL-SLAM (their κ‖R_j − R_i R_ij‖²_F equals 2κ|r_j − r_i R_ij|² for planar rotations)"))' \
'--tol=[Relative suboptimality bound under which the estimate is called certified]:REL:_default' \
'--rerun-save=[Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with \`rerun PATH.rrd\`]:PATH.rrd:_default' \
'--rerun-connect=[Stream the recording to a running rerun viewer, at URL if given \[default\: rerun+http\://127.0.0.1\:9876/proxy\]; an unreachable viewer is a warning]::URL:_default' \
'--strict[Treat unknown tags as errors instead of skipping them with a warning]' \
'(--strict)--ignore-equiv[Skip TORO'\''s EQUIV lines (vertex merges, not implemented) with a warning instead of refusing the file\: the graph is then the file'\''s without them]' \
'--allow-indefinite[Accept noise matrices that are not positive definite (the solvers take them only with --weights unit)]' \
'--json[Print the report as one JSON object on stdout]' \
'-q[No progress display (shown on stderr only when stderr is a terminal)]' \
'--quiet[No progress display (shown on stderr only when stderr is a terminal)]' \
'(-q --quiet)--progress[Show the progress even when stderr is not a terminal, as plain lines (for logs)]' \
'--rerun-spawn[Start a rerun viewer (the \`rerun\` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it]' \
'-h[Print help (see more with '\''--help'\'')]' \
'--help[Print help (see more with '\''--help'\'')]' \
'-V[Print version]' \
'--version[Print version]' \
':input -- Input file, or - for stdin:_default' \
&& ret=0
}

(( $+functions[_pgo-certify_commands] )) ||
_pgo-certify_commands() {
    local commands; commands=()
    _describe -t commands 'pgo-certify commands' commands "$@"
}

if [ "$funcstack[1]" = "_pgo-certify" ]; then
    _pgo-certify "$@"
else
    compdef _pgo-certify pgo-certify
fi
