fn main() -> std::process::ExitCode {
    pgo::cli::convert::main()
}
