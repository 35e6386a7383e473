"""The project's benchmarks: ``python -m benchmarks [NAME ...] [--write] [--quick]``
(benchmarks/__main__.py) runs them; each bench_*.py also runs on its own as a script.
What they share (clocks, the machine line, the writer of the docs' marker blocks, the C
importer) is benchmarks/harness.py."""
