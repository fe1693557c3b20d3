_pgo__solve() {
    local i cur prev opts cmd
    COMPREPLY=()
    if [[ "${BASH_VERSINFO[0]}" -ge 4 ]]; then
        cur="$2"
    else
        cur="${COMP_WORDS[COMP_CWORD]}"
    fi
    prev="$3"
    cmd=""
    opts=""

    for i in "${COMP_WORDS[@]:0:COMP_CWORD}"
    do
        case "${cmd},${i}" in
            ",$1")
                cmd="pgo__solve"
                ;;
            *)
                ;;
        esac
    done

    case "${cmd}" in
        pgo__solve)
            opts="-o -q -h -V --from --dialect --strict --ignore-equiv --allow-indefinite --output --to --weights --method --solver --tol --max-rank --staircase-budget --refine --robust --inlier-threshold --all-edges-uncertain --warm-start --certify-inner --drop-outliers --marginals --fail-uncertified --json --no-timings --quiet --progress --rerun-save --rerun-connect --rerun-spawn --help --version"
            if [[ ${cur} == -* || ${COMP_CWORD} -eq 1 ]] ; then
                COMPREPLY=( $(compgen -W "${opts}" -- "${cur}") )
                return 0
            fi
            case "${prev}" in
                --from)
                    COMPREPLY=($(compgen -W "g2o toro" -- "${cur}"))
                    return 0
                    ;;
                --dialect)
                    COMPREPLY=($(compgen -W "g2o toro-info toro-cov g2o-cov" -- "${cur}"))
                    return 0
                    ;;
                --output)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                -o)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --to)
                    COMPREPLY=($(compgen -W "g2o toro" -- "${cur}"))
                    return 0
                    ;;
                --weights)
                    COMPREPLY=($(compgen -W "unit isotropic" -- "${cur}"))
                    return 0
                    ;;
                --method)
                    COMPREPLY=($(compgen -W "auto sdp staircase" -- "${cur}"))
                    return 0
                    ;;
                --solver)
                    COMPREPLY=($(compgen -W "ipm clarabel" -- "${cur}"))
                    return 0
                    ;;
                --tol)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --max-rank)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --staircase-budget)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --robust)
                    COMPREPLY=($(compgen -W "tls gm" -- "${cur}"))
                    return 0
                    ;;
                --inlier-threshold)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --marginals)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --rerun-save)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --rerun-connect)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                *)
                    COMPREPLY=()
                    ;;
            esac
            COMPREPLY=( $(compgen -W "${opts}" -- "${cur}") )
            return 0
            ;;
    esac
}

if [[ "${BASH_VERSINFO[0]}" -eq 4 && "${BASH_VERSINFO[1]}" -ge 4 || "${BASH_VERSINFO[0]}" -gt 4 ]]; then
    complete -F _pgo__solve -o nosort -o bashdefault -o default pgo-solve
else
    complete -F _pgo__solve -o bashdefault -o default pgo-solve
fi
