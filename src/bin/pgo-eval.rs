fn main() -> std::process::ExitCode {
    pgo::cli::eval::main()
}
