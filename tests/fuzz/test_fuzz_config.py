"""Bad input to the run-config loader (tightknot/app/config.py, issue 8): any mapping or any
file gives a TieConfig within the documented ranges or a ValueError naming the key (or the
file); nothing else escapes."""

from __future__ import annotations

import json
import math

from hypothesis import given, settings
from hypothesis import strategies as st

from tightknot.app.config import TieConfig, config_from_dict, config_keys, load_config

KEYS = config_keys()
value = st.one_of(st.none(), st.booleans(), st.integers(-10**7, 10**7),
                  st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
                  st.sampled_from(["closed", "open", "kappa_D0", "contact_width", "cpu"]),
                  st.lists(st.integers(), max_size=2), st.dictionaries(st.text(max_size=3),
                                                                      st.integers(), max_size=1))
mapping = st.dictionaries(st.one_of(st.sampled_from(KEYS), st.text(max_size=8)), value,
                          max_size=6)
#: Mostly valid configs with one key changed: reaches the checks behind the first one.
base = st.sampled_from([{"knot": "closed"}, {"knot": "open", "force": 2.0},
                        {"knot": "open", "target_lambda": 12.0, "length": 0.125}])


def _check_config(cfg: TieConfig) -> None:
    assert cfg.knot in ("closed", "open")
    for k, v in cfg.to_dict().items():
        if isinstance(v, float):
            assert math.isfinite(v), k
    assert cfg.nodes is not None and cfg.nodes >= 24
    if cfg.knot == "open":
        assert sum(cfg.to_dict()[k] is not None for k in
                   ("force", "end_distance", "target_lambda")) == 1


def _check_error(err: ValueError, data) -> None:
    msg = str(err)
    assert msg.strip()
    if isinstance(data, dict):
        # It names a key (or says the config is not a mapping / which key is unknown).
        assert any(k in msg for k in KEYS) or "key" in msg, msg


@settings(max_examples=100)
@given(data=st.one_of(mapping, value))
def test_any_mapping(data) -> None:
    try:
        cfg = config_from_dict(data)
    except ValueError as err:
        _check_error(err, data)
        return
    _check_config(cfg)


@settings(max_examples=100)
@given(b=base, key=st.sampled_from(KEYS), v=value)
def test_one_key_changed(b: dict, key: str, v) -> None:
    data = dict(b, **{key: v})
    try:
        cfg = config_from_dict(data)
    except ValueError as err:
        _check_error(err, data)
        return
    _check_config(cfg)


@settings(max_examples=40)
@given(payload=st.one_of(st.text(max_size=80), st.binary(max_size=80).map(
    lambda b: b.decode("latin-1")), mapping.map(lambda d: json.dumps(d, default=str))),
    suffix=st.sampled_from([".json", ".toml", ".txt", ""]))
def test_any_file(tmp_path_factory, payload: str, suffix: str) -> None:
    path = tmp_path_factory.mktemp("cfg") / f"config{suffix}"
    path.write_text(payload, encoding="utf-8")
    try:
        cfg = load_config(path)
    except ValueError as err:
        assert str(path) in str(err), str(err)  # the file is named
        return
    _check_config(cfg)


def test_undecodable_file_is_a_clean_error(tmp_path) -> None:
    # Found by this fuzzing (a UnicodeDecodeError without the file name); fixed in e6fbcc1.
    path = tmp_path / "config.json"
    path.write_bytes(b"\xff\xfe{\x00")
    try:
        load_config(path)
    except ValueError as err:
        assert str(path) in str(err)
    else:
        raise AssertionError("bytes that are not UTF-8 must be refused")
