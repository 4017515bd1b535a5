"""The body of one stored session: its metrics document and the suggestions made from it."""

from __future__ import annotations

from pydantic import Field

from backend.sessions.schemas import SessionItemOut
from backend.suggestions.schemas import SuggestionOut
from kinect_agent.analysis.document import AnalysisDocument


class SessionOut(SessionItemOut):
    """A stored session with its metrics document and the suggestions it produced that the caller may see."""

    metrics: AnalysisDocument | None = Field(
        description="the analysis document (kinect_agent.analysis.document) with its indicators, upgraded to today's "
        "schema_version; each reason (Reason) and each indicator's basis (Basis) with its id and params as stored "
        "and its text in the reader's language; null: not analysed"
    )
    suggestions: list[SuggestionOut]
