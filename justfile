# rocklab recipes (convenience only: every recipe is a plain cargo command).

default: check

# rustc overflows its default stack compiling polars in the bench (optimised) profile.
export RUST_MIN_STACK := "16777216"

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

# Peak memory of the whole `reduce` command on the benchmark's 2,000,000-row log,
# and on the same rows with 16 channels (242 MB; issue 22 bounds it at 150 MB).
bench-mem: bench
    cargo build --release
    /usr/bin/time -v target/release/rocklab reduce target/bench-data/campaign.toml --out target/bench-data/out --no-plots 2>&1 | grep -E "Maximum resident|Elapsed"
    /usr/bin/time -v target/release/rocklab reduce target/bench-data/campaign_wide.toml --out target/bench-data/out_wide --no-plots 2>&1 | grep -E "Maximum resident|Elapsed"

# The Python package (python/): release build and install, as the README says.
python-install:
    pip install ./python

# Debug build of the extension, installed, then the pytest suite (what CI runs).
python-test:
    cd python && python3 -m maturin build --profile dev --out ../target/wheels
    pip install --force-reinstall --no-deps target/wheels/rocklab-*.whl
    python3 -m pytest python/tests -q

# The example notebook: figures into python/examples/out/.
python-example:
    python3 python/examples/notebook.py
