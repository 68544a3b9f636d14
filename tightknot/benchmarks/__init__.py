"""Benchmarks behind ``tightknot bench`` and the scripts in ``bench/``."""
