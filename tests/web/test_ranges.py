"""The Range and conditional headers of a result file, settled before Starlette serves it
(startrack.web._ranges, startrack.web._conditional)."""

from __future__ import annotations

import pytest

from startrack.web._conditional import not_modified
from startrack.web._ranges import byte_ranges, settle_range
from startrack.web._refusals import Refusal

SIZE = 1000  # bytes


@pytest.mark.parametrize(("value", "expected"), [
    ("bytes=0-9", [(0, 9)]),
    ("bytes=990-", [(990, 999)]),
    ("bytes=-10", [(990, 999)]),
    ("bytes=-5000", [(0, 999)]),
    ("bytes=995-2000", [(995, 999)]),
    ("Bytes = 0-1 , ,5-6", [(0, 1), (5, 6)]),
    ("bytes=0-1,2000-3000", [(0, 1)]),  # the satisfiable one is kept (Starlette refused the set)
    ("bytes=1000-", []),
    ("bytes=-0", []),
])
def test_valid_sets_give_their_satisfiable_ranges(value, expected):
    assert byte_ranges(value, SIZE) == expected


@pytest.mark.parametrize("value", ["items=0-5", "bytes", "bytes=", "bytes=abc", "bytes=5-2", "bytes=-", "bytes=1-2-3",
                                   "bytes=0x10-20", "bytes=+1-2"])
def test_invalid_sets_are_none(value):
    assert byte_ranges(value, SIZE) is None


def scope_with(*headers: tuple[str, str]) -> dict:
    return {"headers": [(b"host", b"x")] + [(k.encode(), v.encode()) for k, v in headers]}


def test_an_invalid_set_or_another_versions_if_range_drops_the_header():
    for headers in ((("range", "items=0-5"),), (("range", "bytes=0-5"), ("if-range", '"old"'))):
        scope = scope_with(*headers)
        settle_range(scope, SIZE, ('"new"', "Mon, 07 Dec 2026 06:00:00 GMT"), "x.csv")
        assert scope["headers"] == [(b"host", b"x")]


def test_a_valid_set_is_rewritten_to_its_satisfiable_ranges():
    scope = scope_with(("Range", "bytes=-10, 5000-"), ("If-Range", '"new"'))
    settle_range(scope, SIZE, ('"new"', ""), "x.csv")
    assert scope["headers"] == [(b"host", b"x"), (b"range", b"bytes=990-999")]


def test_a_set_past_the_end_is_a_416_naming_the_size():
    with pytest.raises(Refusal) as info:
        settle_range(scope_with(("range", "bytes=1000-")), SIZE, ("", ""), "x.csv")
    assert info.value.status == 416 and info.value.headers == {"Content-Range": "bytes */1000"}
    assert "x.csv" in info.value.message and "1000 bytes" in info.value.message and "0 to 999" in info.value.message


ETAG, MODIFIED = '"abc"', "Mon, 07 Dec 2026 06:00:00 GMT"


@pytest.mark.parametrize(("headers", "expected"), [
    ({}, False),
    ({"if-none-match": '"abc"'}, True),
    ({"if-none-match": 'W/"abc", "x"'}, True),  # weak comparison
    ({"if-none-match": "*"}, True),
    ({"if-none-match": '"other"', "if-modified-since": MODIFIED}, False),  # If-None-Match decides
    ({"if-modified-since": MODIFIED}, True),
    ({"if-modified-since": "Tue, 08 Dec 2026 06:00:00 GMT"}, True),
    ({"if-modified-since": "Sun, 06 Dec 2026 06:00:00 GMT"}, False),
    ({"if-modified-since": "yesterday"}, False),  # an unreadable date is ignored
    ({"if-modified-since": "Mon, 07 Dec 2026 06:00:00"}, False),  # no zone: not an HTTP date
])
def test_a_current_copy_is_not_sent_again(headers, expected):
    assert not_modified(headers, ETAG, MODIFIED) is expected
