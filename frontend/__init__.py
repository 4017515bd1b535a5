"""The web pages: login, the patient's feedback screen, the therapist's dashboard and patient detail, 3D replay.

Pages are HTML shells rendered by frontend.pages; their scripts (static/*.js) read and change data only through the
REST API under /api/v1 with the login cookie and the X-CSRF-Token header.
"""
