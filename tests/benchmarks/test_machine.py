"""The machine line every benchmark table starts with tells processor generations apart."""
from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks"))

from machine import cpu_description  # noqa: E402

ZEN5 = """processor\t: 0
vendor_id\t: AuthenticAMD
cpu family\t: 26
model\t\t: 2
model name\t: AMD EPYC
flags\t\t: fpu sse2 avx avx2 fma avx512f avx512dq

processor\t: 1
cpu family\t: 99
"""

ZEN3 = "cpu family\t: 25\nmodel\t\t: 1\nmodel name\t: AMD EPYC\nflags\t\t: fpu sse2 avx avx2 fma\n"


def test_the_cpu_line_gives_family_model_and_the_widest_vector_instructions():
    assert cpu_description(ZEN5) == "AMD EPYC (family 26, model 2; AVX-512)"
    assert cpu_description(ZEN3) == "AMD EPYC (family 25, model 1; AVX2)"


def test_the_cpu_line_reads_only_the_first_processor():
    assert "99" not in cpu_description(ZEN5)


def test_the_cpu_line_without_family_is_the_model_name_alone():
    assert cpu_description("model name\t: Some CPU\n") == "Some CPU"
