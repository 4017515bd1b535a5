"""The progress report of one patient over a period, as a PDF a referring doctor reads (reportlab).

Black-and-white safe: every series has its own marker and dash, every chart has its table beside it. Paper A4 or
Letter. Sections: plan and adherence, repetitions and range of motion over time with the exercise's MDC95,
balance, data quality, the therapist's notes, pain (0-10 numeric rating scale) and effort (Borg CR10) the patient
said after each set, who and when.
"""

from __future__ import annotations

import datetime as dt
import io
import math
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from reportlab.graphics.charts.lineplots import LinePlot
from reportlab.graphics.shapes import Drawing, String
from reportlab.graphics.widgets.markers import makeMarker
from reportlab.lib import colors
from reportlab.lib.pagesizes import A4, LETTER
from reportlab.lib.styles import getSampleStyleSheet
from reportlab.lib.units import mm
from reportlab.platypus import KeepTogether, Paragraph, SimpleDocTemplate, Spacer, Table, TableStyle
from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.exceptions import InvalidInput
from backend.exercises.models import Exercise
from backend.feeling.models import SessionFeeling
from backend.i18n import ENGLISH
from backend.plans.models import Plan, PlanItem
from backend.session_texts.reasons import written
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.suggestions import service as suggestions
from backend.suggestions.models import Suggestion
from backend.users.models import User
from kinect_agent.analysis.document import read_if_readable
from kinect_agent.analysis.mdc import rom_mdc95

PAPERS = {"a4": A4, "letter": LETTER}
DEFAULT_DAYS = 28  # a period nobody chose: the last 4 weeks, its last day included (API, CLI and the page's form)
MARKERS = ("FilledCircle", "FilledSquare", "FilledTriangle", "Cross", "FilledDiamond", "Circle")
DASHES = (None, (4, 2), (1, 2), (6, 2, 1, 2), (2, 2), (8, 3))


@dataclass(frozen=True)
class Period:
    """The report's days, first and last included (dates, UTC)."""

    start: dt.date
    end: dt.date

    @property
    def weeks(self) -> float:
        """Returns the length in weeks (days / 7)."""
        return ((self.end - self.start).days + 1) / 7.0

    @classmethod
    def asked(cls, start: dt.date | None, end: dt.date | None) -> Period:
        """Returns the period a caller asked for: `end` defaults to today (UTC), `start` to DEFAULT_DAYS days up to
        `end` (both included).

        Raises InvalidInput when it runs backwards or lasts more than 3 years.
        """
        end = end or dt.datetime.now(dt.UTC).date()
        start = start or end - dt.timedelta(days=DEFAULT_DAYS - 1)
        if start > end or (end - start).days > 3 * 366:
            raise InvalidInput(f"the period from={start} to={end} must run forwards and last at most 3 years")
        return cls(start, end)


def _p(text: str, style: Any) -> Paragraph:
    return Paragraph(text.replace("&", "&amp;").replace("<", "&lt;"), style)


def _table(rows: list[list[Any]], widths: list[float] | None = None) -> Table:
    t = Table(rows, colWidths=widths, repeatRows=1)
    t.setStyle(TableStyle([
        ("FONT", (0, 0), (-1, 0), "Helvetica-Bold", 8.5), ("FONT", (0, 1), (-1, -1), "Helvetica", 8.5),
        ("LINEBELOW", (0, 0), (-1, 0), 0.8, colors.black), ("LINEBELOW", (0, -1), (-1, -1), 0.4, colors.black),
        ("ROWBACKGROUNDS", (0, 1), (-1, -1), [colors.white, colors.Color(0.93, 0.93, 0.93)]),
        ("VALIGN", (0, 0), (-1, -1), "TOP"),
    ]))  # fmt: skip
    return t


def _chart(title: str, series: dict[str, list[tuple[float, float]]], y_label: str, width: float, start: dt.date,
           y_range: tuple[float, float] | None = None) -> Drawing:  # fmt: skip
    """Returns a line chart of {label: [(day number, value)]}, day 0 = start, one marker and dash per series, in
    black; the x axis ticks whole days, each labelled once with its date; y_range: the y axis's (min, max), else
    fitted to the data."""
    d = Drawing(width, 60 * mm)
    plot = LinePlot()
    plot.x, plot.y, plot.width, plot.height = 12 * mm, 10 * mm, width - 16 * mm, 40 * mm
    plot.data = [pts for pts in series.values()]
    for i, _ in enumerate(series):
        line = plot.lines[i]
        line.strokeColor = colors.black
        line.strokeWidth = 1
        line.symbol = makeMarker(MARKERS[i % len(MARKERS)], size=4)
        if DASHES[i % len(DASHES)]:
            line.strokeDashArray = DASHES[i % len(DASHES)]
    if y_range is not None:
        plot.yValueAxis.valueMin, plot.yValueAxis.valueMax = y_range
    days = [x for pts in series.values() for x, _ in pts]
    first, last = math.floor(min(days, default=0.0)), math.ceil(max(days, default=0.0))
    last = max(last, first + 1)
    plot.xValueAxis.valueMin, plot.xValueAxis.valueMax = first, last
    plot.xValueAxis.valueStep = max(1, math.ceil((last - first) / 7))  # at most 8 ticks, whole days
    plot.xValueAxis.labelTextFormat = lambda x: (start + dt.timedelta(days=round(x))).strftime("%d %b")
    plot.xValueAxis.labels.fontSize = plot.yValueAxis.labels.fontSize = 7
    d.add(plot)
    d.add(String(0, 55 * mm, title, fontName="Helvetica-Bold", fontSize=9))
    d.add(String(0, 51 * mm, y_label, fontName="Helvetica", fontSize=7))
    legend = "   ".join(f"{MARKERS[i % len(MARKERS)].replace('Filled', 'filled ').lower()}: {k}"
                       for i, k in enumerate(series))  # fmt: skip
    d.add(String(0, 0, legend, fontName="Helvetica", fontSize=7))
    return d


def _feeling_section(rows: Sequence[Any], period: Period, body: Any, width: float) -> list[Any]:
    """Returns the paragraphs, chart and table of the pain and effort the patient said after the period's sets."""
    said = [r for r in rows if r.pain_nrs is not None or r.effort_cr10 is not None]
    if not said:
        return [_p("The patient did not say how any set of this period felt (asked after each set; skipping is "
                   "allowed).", body)]  # fmt: skip
    pains = [r.pain_nrs for r in said if r.pain_nrs is not None]
    text = f"Said after {len(said)} of {len(rows)} set(s): pain on the 0-10 numeric rating scale, effort on the "
    text += "Borg CR10 scale (0 nothing at all, 10 maximal)."
    if pains:
        text += f" Pain: highest {max(pains)}, last {pains[-1]} of 10."

    def day(r: Any) -> float:
        return float((r.started_at.date() - period.start).days)

    series = {
        "pain (0-10)": [(day(r), float(r.pain_nrs)) for r in said if r.pain_nrs is not None],
        "effort (Borg CR10)": [(day(r), float(r.effort_cr10)) for r in said if r.effort_cr10 is not None],
    }
    out = [_p(text, body)]
    if max(len(v) for v in series.values()) >= 2:
        out.append(
            _chart(
                "Pain and effort after each set",
                {k: v for k, v in series.items() if v},
                "of 10",
                width,
                period.start,
                (0.0, 10.0),
            )
        )
    table = [["Date", "Exercise", "Pain (0-10)", "Effort (Borg CR10)"]]
    for r in said:
        table.append([f"{r.started_at:%d %b %Y %H:%M}", r.name, "skipped" if r.pain_nrs is None else str(r.pain_nrs),
                      "skipped" if r.effort_cr10 is None else f"{r.effort_cr10:g}"])  # fmt: skip
    out.append(_table(table, [40 * mm, 50 * mm, 30 * mm, 38 * mm]))
    return out


def build_report(*, db_session: Session, patient: User, period: Period, made_by: str, paper: str = "a4") -> bytes:
    """Returns the PDF bytes of the progress report of `patient` over `period`, made by `made_by` (words)."""
    styles = getSampleStyleSheet()
    body, h1, h2 = styles["BodyText"], styles["Title"], styles["Heading2"]
    body.fontSize, body.leading = 9.5, 12.5
    page_w, page_h = PAPERS[paper]
    margin = 18 * mm
    width = page_w - 2 * margin
    start = dt.datetime.combine(period.start, dt.time(), tzinfo=dt.UTC)
    end = dt.datetime.combine(period.end + dt.timedelta(days=1), dt.time(), tzinfo=dt.UTC)
    rows = db_session.execute(
        select(ExerciseSession.started_at, Exercise.slug, Exercise.name, SessionMetric.repetitions,
               SessionMetric.rom_deg, SessionMetric.quality_ok, SessionMetric.document, SessionFeeling.pain_nrs,
               SessionFeeling.effort_cr10)
        .join(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .outerjoin(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
        .where(ExerciseSession.patient_id == patient.id, ExerciseSession.started_at >= start,
               ExerciseSession.started_at < end)
        .order_by(ExerciseSession.started_at)
    ).all()  # fmt: skip
    made = dt.datetime.now(dt.UTC)
    story = [
        _p(f"Progress report: {patient.full_name or patient.email}", h1),
        _p(
            f"Patient {patient.id}, {patient.email}. Period {period.start:%d %b %Y} to {period.end:%d %b %Y} "
            f"({period.weeks:.1f} weeks). Made {made:%d %b %Y %H:%M} UTC by {made_by}.",
            body,
        ),  # fmt: skip
        Spacer(1, 4 * mm),
        _p("Plan and adherence", h2),
    ]
    plans = db_session.scalars(select(Plan).where(Plan.patient_id == patient.id, Plan.start_date <= period.end)
                               .order_by(Plan.start_date)).all()  # fmt: skip
    plans = [p for p in plans if p.end_date is None or p.end_date >= period.start]
    done: defaultdict[str, int] = defaultdict(int)
    for r in rows:
        done[r.slug] += 1
    adherence = [["Plan", "Exercise", "Prescribed", "Planned", "Done", "Adherence"]]
    for plan in plans:
        first = max(plan.start_date, period.start)
        last = min(plan.end_date or period.end, period.end)
        weeks = max(((last - first).days + 1) / 7.0, 0.0)
        items = db_session.execute(select(PlanItem, Exercise.slug, Exercise.name).join(Exercise)
                                   .where(PlanItem.plan_id == plan.id).order_by(PlanItem.position)).all()  # fmt: skip
        for item, slug, name in items:
            planned = round(item.frequency_per_week * weeks)
            share = f"{100 * done[slug] / planned:.0f} %" if planned else "–"
            adherence.append([plan.title, name, f"{item.sets} × {item.repetitions}, {item.frequency_per_week}/week",
                              str(planned), str(done[slug]), share])  # fmt: skip
    if len(adherence) == 1:
        story.append(_p("No plan was running in this period.", body))
    else:
        story.append(_table(adherence, [32 * mm, 38 * mm, 36 * mm, 24 * mm, 22 * mm, 20 * mm]))
    story += [Spacer(1, 3 * mm), _p("Repetitions and range of motion", h2)]
    by_ex: dict[str, list[Any]] = defaultdict(list)
    for r in rows:
        by_ex[r.name].append(r)
    if not rows:
        story.append(_p("No session was recorded in this period.", body))
    for name, rs in by_ex.items():
        slug = rs[0].slug
        mdc = rom_mdc95(slug)
        roms = [(float((r.started_at.date() - period.start).days), r.rom_deg) for r in rs if r.rom_deg is not None]
        reps = [(float((r.started_at.date() - period.start).days), float(r.repetitions)) for r in rs
                if r.repetitions is not None]  # fmt: skip
        text = f"{name}: {len(rs)} session(s)."
        if len(roms) >= 2:
            change = roms[-1][1] - roms[0][1]
            text += f" Range of motion {roms[0][1]:.0f}° → {roms[-1][1]:.0f}° ({change:+.0f}°"
            if mdc:
                verdict = "a real change" if abs(change) > mdc else "within the measurement's noise"
                text += f"; MDC95 {mdc:.0f}°: {verdict})."
            else:
                text += "; no MDC measured for this exercise)."
        block = [_p(text, body)]
        if len(roms) >= 2 or len(reps) >= 2:
            block.append(
                _chart(name, {"range of motion, degrees": roms, "repetitions": reps}, "value", width, period.start)
            )
        table = [["Date", "Repetitions", "Range of motion", "Balance sway", "Data quality"]]
        why_no_sway: list[str] = []  # each reason once, in the order the sessions first give it
        for r in rs:
            doc = read_if_readable(r.document)
            sway = doc.balance.sway_velocity_m_s if doc is not None and doc.balance is not None else None
            if sway is None and doc is not None and doc.balance_missing is not None:
                why = written(doc.balance_missing, ENGLISH)
                why_no_sway += [why] if why not in why_no_sway else []
            table.append([f"{r.started_at:%d %b %Y %H:%M}", "–" if r.repetitions is None else str(r.repetitions),
                          "–" if r.rom_deg is None else f"{r.rom_deg:.0f}°",
                          "not measured" if sway is None else f"{100 * sway:.1f} cm/s",
                          {True: "good", False: "poor", None: "–"}[r.quality_ok]])  # fmt: skip
        block.append(_table(table, [40 * mm, 26 * mm, 32 * mm, 32 * mm, 28 * mm]))
        story += [KeepTogether(block[:2]), block[-1]]
        if why_no_sway:
            story.append(_p("Balance not measured: " + " ".join(why_no_sway), body))
        story.append(Spacer(1, 3 * mm))
    ok = sum(1 for r in rows if r.quality_ok)
    story += [_p("Data quality", h2),
              _p(f"{ok} of {len(rows)} session(s) had good tracking (the camera saw the body well enough for the "
                 "numbers above to be trusted); read the others with care." if rows else "No session.", body),
              _p("Pain and effort", h2)]  # fmt: skip
    story += _feeling_section(rows, period, body, width)
    story.append(_p("Therapist's notes", h2))
    notes = db_session.execute(
        select(Suggestion.created_at, Suggestion.text, User.full_name).outerjoin(User, User.id == Suggestion.author_id)
        .where(Suggestion.patient_id == patient.id, Suggestion.source == "therapist",
               Suggestion.created_at >= start, Suggestion.created_at < end)
        .order_by(Suggestion.created_at)
    ).all()  # fmt: skip
    plan_notes = [(p.title, p.notes) for p in plans if p.notes]
    for title, note in plan_notes:
        story.append(_p(f"Plan “{title}”: {note}", body))
    for n in notes:
        story.append(_p(f"{n.created_at:%d %b %Y}, {n.full_name or 'therapist'}: {n.text}", body))
    if not notes and not plan_notes:
        story.append(_p("No note in this period.", body))
    story.append(_p("Advice from the rules, approved", h2))
    advice = db_session.scalars(
        select(Suggestion).where(Suggestion.patient_id == patient.id, Suggestion.source == "system",
                                 Suggestion.status == "approved", Suggestion.created_at >= start,
                                 Suggestion.created_at < end)
        .order_by(Suggestion.created_at, Suggestion.id)
    ).all()  # fmt: skip
    for a in advice:  # in the report's language (English), whatever the patient's was when the rule ran
        story.append(_p(f"{a.created_at:%d %b %Y}: {suggestions.shown_text(a, ENGLISH)[0]}", body))
    if not advice:
        story.append(_p("No approved advice in this period.", body))

    def footer(canvas: Any, doc: Any) -> None:
        canvas.saveState()
        canvas.setFont("Helvetica", 7.5)
        canvas.drawString(margin, 10 * mm, f"Kinect Home Coach · patient {patient.id} · {period.start} to "
                                           f"{period.end} · made {made:%Y-%m-%d %H:%M} UTC by {made_by}")  # fmt: skip
        canvas.drawRightString(page_w - margin, 10 * mm, f"page {doc.page}")
        canvas.restoreState()

    out = io.BytesIO()
    doc = SimpleDocTemplate(out, pagesize=PAPERS[paper], leftMargin=margin, rightMargin=margin, topMargin=margin,
                            bottomMargin=20 * mm, title=f"Progress report, patient {patient.id}",
                            author="Kinect Home Coach")  # fmt: skip
    doc.build(story, onFirstPage=footer, onLaterPages=footer)
    return out.getvalue()
