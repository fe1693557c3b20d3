fn main() -> std::process::ExitCode {
    pgo::cli::simulate::main()
}
