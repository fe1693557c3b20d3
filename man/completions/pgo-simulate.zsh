#compdef pgo-simulate

autoload -U is-at-least

_pgo-simulate() {
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
'--world=[The world\: planar (the paper'\''s model (47)), or an SE(3) world written as g2o 3D (see 3D worlds below)]:WORLD:((planar\:"Planar poses by the paper'\''s model (47)"
sphere\:"SE(3) poses on rings of latitude of a sphere (like sphere2500)"
torus\:"SE(3) poses on rings around a torus (like torus3D)"
grid\:"SE(3) poses walking a cubic lattice (like grid3D)"))' \
'-n+[Number of poses (ids 0..N-1)]:N:_default' \
'--poses=[Number of poses (ids 0..N-1)]:N:_default' \
'--loop-probability=[Probability P_c of a loop closure between two poses i < j with j > i + 1, each pair independently (per pose with --loop-model per-pose; in a 3D world each candidate) \[default\: 0.1, 1 in a 3D world\]]:P:_default' \
'--loop-model=[Which loop closures are drawn (planar) \[default\: pairs\]]:MODEL:((pairs\:"The paper'\''s model (47)\: every pair (i, j), j > i + 1, with probability P_c (about P_c n^2/2 loop closures\: for small n)"
per-pose\:"Each pose j >= 2 with probability P_c closes one loop to an earlier pose drawn uniformly (about P_c n loop closures\: linear in n)"))' \
'--rotation-noise=[Rotation noise e_R\: gaussian\:SIGMA (normal, standard deviation SIGMA radians) or uniform (uniform in (-pi, pi\])]:SPEC:_default' \
'--translation-noise=[Translation noise e_Delta\: gaussian\:SIGMA (normal in each coordinate, standard deviation SIGMA metres) or uniform\:HALFWIDTH (uniform in \[-HALFWIDTH, HALFWIDTH\]^2)]:SPEC:_default' \
'--seed=[Seed of the random number generator (any 64-bit unsigned integer)]:S:_default' \
'--side=[Side L of the square the positions are drawn from, in metres]:L:_default' \
'--landmarks=[Landmarks M\: positions uniform in the square, observed (d = R_i^T (l - p_i) + e, e the translation noise) from every pose within --landmark-range; written as VERTEX_XY (ids N, N+1, ..., the landmarks some pose sees) and EDGE_SE2_XY lines]:M:_default' \
'--landmark-range=[A pose observes the landmarks within this distance, in metres]:R:_default' \
'-o+[Output file, or - for stdout]:OUT:_default' \
'--output=[Output file, or - for stdout]:OUT:_default' \
'--to=[Output format \[default\: from the output'\''s extension (.g2o, .graph), else g2o\]]:FORMAT:((g2o\:"g2o\: \`VERTEX_SE2\`, \`EDGE_SE2\`, \`FIX\` (docs/formats.md §2)"
toro\:"TORO\: \`VERTEX2\`/\`VERTEX\`, \`EDGE2\`/\`EDGE\` (docs/formats.md §3)"))' \
'(--world -n --poses --loop-probability --loop-model --force --rotation-noise --translation-noise --side)--corrupt=[Add false loop closures to this graph (- for stdin) instead of generating one (see Outliers below)]:GRAPH:_default' \
'--outliers=[Number of outlier groups to add to --corrupt'\''s graph]:N:_default' \
'--outlier-model=[Which pose pairs outliers join\: random (any two poses) or local (at most 20 ids apart)]:MODEL:((random\:"Any two poses, uniformly"
local\:"Poses at most 20 ids apart"))' \
'--group=[Outliers per group\: G consecutive pairs (v1+k, v2+k) sharing one measurement]:G:_default' \
'--outlier-list=[Write the list of the added outliers here\: one line '\''LINE I J'\'' each]:FILE:_default' \
'--rerun-save=[Write a rerun recording of the run to this .rrd file (poses, edges, residuals, solver iterations, eigenvalues, certificate); open it with \`rerun PATH.rrd\`]:PATH.rrd:_default' \
'--rerun-connect=[Stream the recording to a running rerun viewer, at URL if given \[default\: rerun+http\://127.0.0.1\:9876/proxy\]; an unreachable viewer is a warning]::URL:_default' \
'--force[Generate however many loop closures the pairs model makes (see Size below)]' \
'-q[Do not print the summary line on stderr]' \
'--quiet[Do not print the summary line on stderr]' \
'--rerun-spawn[Start a rerun viewer (the \`rerun\` executable on PATH, e.g. from PyPI rerun-sdk==0.36.3) and stream the recording to it]' \
'-h[Print help (see more with '\''--help'\'')]' \
'--help[Print help (see more with '\''--help'\'')]' \
'-V[Print version]' \
'--version[Print version]' \
&& ret=0
}

(( $+functions[_pgo-simulate_commands] )) ||
_pgo-simulate_commands() {
    local commands; commands=()
    _describe -t commands 'pgo-simulate commands' commands "$@"
}

if [ "$funcstack[1]" = "_pgo-simulate" ]; then
    _pgo-simulate "$@"
else
    compdef _pgo-simulate pgo-simulate
fi
