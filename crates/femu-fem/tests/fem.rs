//! Evidence for the finite element core, gathered in one test binary.

mod fem {
    mod align;
    mod assembly;
    mod beam3;
    pub mod common;
    mod constraints;
    mod convergence;
    mod elements;
    mod incompatible;
    mod locate;
    mod mesh;
    mod pyramids;
    mod refine;
    mod shell;
    mod shell8;
    mod structural;
}
