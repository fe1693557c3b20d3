#[global_allocator]
static ALLOCATOR: pgo::cli::allocator::Allocator = pgo::cli::allocator::Allocator;

fn main() -> std::process::ExitCode {
    pgo::cli::spectrum::main()
}
