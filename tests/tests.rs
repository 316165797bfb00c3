//! End-to-end tests through the `femu` facade, gathered in one binary (ripgrep's layout).

mod e2e {
    mod docs;
    mod modes;
}
