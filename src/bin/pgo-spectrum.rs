fn main() -> std::process::ExitCode {
    pgo::cli::spectrum::main()
}
