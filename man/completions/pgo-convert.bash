_pgo__convert() {
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
                cmd="pgo__convert"
                ;;
            *)
                ;;
        esac
    done

    case "${cmd}" in
        pgo__convert)
            opts="-o -q -h -V --output --from --to --stamps --dialect --to-dialect --reindex --landmarks --landmark-offset --strict --ignore-equiv --allow-indefinite --stats --json --timings --quiet --progress --rerun-save --rerun-connect --rerun-spawn --help --version"
            if [[ ${cur} == -* || ${COMP_CWORD} -eq 1 ]] ; then
                COMPREPLY=( $(compgen -W "${opts}" -- "${cur}") )
                return 0
            fi
            case "${prev}" in
                --output)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                -o)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --from)
                    COMPREPLY=($(compgen -W "g2o toro" -- "${cur}"))
                    return 0
                    ;;
                --to)
                    COMPREPLY=($(compgen -W "g2o toro tum kitti" -- "${cur}"))
                    return 0
                    ;;
                --stamps)
                    COMPREPLY=($(compgen -f "${cur}"))
                    return 0
                    ;;
                --dialect)
                    COMPREPLY=($(compgen -W "g2o toro-info toro-cov g2o-cov" -- "${cur}"))
                    return 0
                    ;;
                --to-dialect)
                    COMPREPLY=($(compgen -W "g2o toro-info toro-cov g2o-cov" -- "${cur}"))
                    return 0
                    ;;
                --landmarks)
                    COMPREPLY=($(compgen -W "g2o landmark2" -- "${cur}"))
                    return 0
                    ;;
                --landmark-offset)
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
    complete -F _pgo__convert -o nosort -o bashdefault -o default pgo-convert
else
    complete -F _pgo__convert -o bashdefault -o default pgo-convert
fi
