# rocklab recipes (convenience only: every recipe is a plain cargo command).

default: check

# Format check, lints and the tests: what CI runs.
check: fmt-check lint test

test:
    cargo test

lint:
    cargo clippy --all-targets -- -D warnings

fmt-check:
    cargo fmt --check

# Reduce the fixture campaigns into reports/demo/.
demo:
    cargo run --release -- demo

# Median time of read + differentiate + peaks on a 2,000,000-row log.
bench:
    cargo bench --bench ingest_peaks

# Peak memory of the whole `reduce` command on the benchmark's 2,000,000-row log.
bench-mem: bench
    cargo build --release
    /usr/bin/time -v target/release/rocklab reduce target/bench-data/campaign.toml --out target/bench-data/out --no-plots 2>&1 | grep -E "Maximum resident|Elapsed"
