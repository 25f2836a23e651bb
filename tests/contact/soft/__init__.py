"""Tests of the soft-granule kernel (perga.contact.soft)."""
