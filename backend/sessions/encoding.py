"""Whether a client takes a gzip-compressed answer, from its Accept-Encoding header (RFC 9110, section 12.5.3)."""

from __future__ import annotations


def accepts_gzip(header: str | None) -> bool:
    """Returns whether an Accept-Encoding header value allows gzip: "gzip" (or "*") listed with a q above 0."""
    if not header:
        return False
    for part in header.split(","):
        name, _, params = part.strip().partition(";")
        if name.strip().lower() not in ("gzip", "*"):
            continue
        q = params.strip().lower()
        if q.startswith("q="):
            try:
                return float(q[2:]) > 0
            except ValueError:
                return False
        return True
    return False
