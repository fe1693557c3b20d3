fn main() -> std::process::ExitCode {
    pgo::cli::solve::main()
}
