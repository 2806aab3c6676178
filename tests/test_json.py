"""The one bounded JSON reader: text that is not text is repaired, never passed on."""

from __future__ import annotations

import json

from studio import loads_json, unpaired_surrogate


def test_a_lone_surrogate_stored_in_a_file_is_read_as_a_replacement_character():
    text = json.dumps(
        {"name": "caf\udce9", "tags": ["\ud800x"], "caf\udce9": 1, "ok": "\U0001f600"}
    )
    value = loads_json(text)
    assert value == {"name": "caf\ufffd", "tags": ["\ufffdx"], "caf\ufffd": 1, "ok": "\U0001f600"}
    assert unpaired_surrogate(value) is None
    assert json.dumps(value, ensure_ascii=False).encode("utf-8")  # now writable as UTF-8


def test_unpaired_surrogate_names_where_it_is():
    assert unpaired_surrogate({"a": [1, {"b": "x\udfff"}]}) == ("a.1.b", "x\udfff")
    assert unpaired_surrogate(["fine", "caf\u00e9"]) is None
