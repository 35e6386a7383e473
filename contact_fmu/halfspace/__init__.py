"""Exact half-space theory (issue 4): Hertz, numerical normal contact, steady rolling."""
