"""A 'lark' module that is not lark 1.x (ROS 2's wheels bring lark-parser
0.12, which installs over it) is one clear error, not a failure deep in
the parser."""
from __future__ import annotations

import lark
import pytest

from htn.jshop.language.errors import HtnError
from htn.jshop.readers import hddl, jshop2, lark_errors


@pytest.mark.parametrize("version", ["0.12.0", "0.7.8", "unknown"])
def test_lark_parser_in_lark_s_place_is_named_with_the_fix(monkeypatch, version):
    monkeypatch.setattr(lark, "__version__", version)
    with pytest.raises(HtnError, match=r"pip install --force-reinstall --no-deps 'lark>=1\.1\.9'"):
        lark_errors.check_lark()


def test_both_readers_check_before_they_build_their_parser(monkeypatch):
    monkeypatch.setattr(lark, "__version__", "0.12.0")
    for reader in (jshop2, hddl):
        reader._lark.cache_clear()
        with pytest.raises(HtnError, match="lark-parser"):
            reader._lark()
        reader._lark.cache_clear()


def test_lark_1_passes():
    lark_errors.check_lark()
