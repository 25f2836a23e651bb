"""Tests of the soft-granule kernel (perga.soft)."""
