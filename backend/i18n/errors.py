"""API error messages in the caller's language: a message marked with N_ where it is raised comes back translated
when the request's Accept-Language names a supported locale (the patient pages send theirs), with
Content-Language saying so; any other message stays as written."""

from __future__ import annotations

from starlette.requests import Request

from backend.i18n import DEFAULT_LOCALE, negotiate, translator


def error_detail(request: Request, message: str) -> tuple[str, dict[str, str]]:
    """Returns the detail of an error for this request and the headers that name its language."""
    locale = negotiate(request.headers.get("accept-language"))
    if locale == DEFAULT_LOCALE:
        return message, {}
    translated = translator(locale).gettext(message)
    return (translated, {"Content-Language": locale}) if translated != message else (message, {})
