fn main() -> std::process::ExitCode {
    pgo::cli::certify::main()
}
