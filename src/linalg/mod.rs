//! Numerical linear algebra, knowing nothing of pose graphs: sparse LLᴴ/LDLᴴ factorizations with
//! their a-posteriori backward errors ([`factor`]) and an LDLᴴ's residual measured ([`residual`]),
//! a block system with its factorization in 32-bit indices where they fit ([`block_system`]), the
//! shift-invert subspace iteration for the smallest eigenvalues of a sparse Hermitian pencil
//! ([`subspace`]), dense Hermitian eigendecompositions ([`eigen`]), the unit roundoffs of double
//! and double-double arithmetic and Higham's γ_k ([`roundoff`]), the seeded generator of random
//! starts and simulations ([`rng`]), anchored weighted Laplacians and their LLᴴ ([`laplacian`]),
//! and independent tasks side by side on two cores with the same bits as on one ([`parallel`]), a
//! supernodal LLᴴ's solves split between two cores by subtrees of the elimination tree, faer's own
//! bits ([`tree_solve`]), its factorization split the same way, the same values on one core as on
//! two ([`tree_factor`]), and the allocator's free memory given back between phases with a factor's
//! room mapped by two threads together ([`heap`]).
//!
//! May use: faer, libc (the allocator) and the standard library only; nothing else of pgo.

pub mod block_system;
pub mod eigen;
pub mod factor;
pub mod heap;
pub mod laplacian;
pub mod parallel;
pub mod residual;
pub mod rng;
pub mod roundoff;
pub mod subspace;
pub mod tree_factor;
pub mod tree_solve;
