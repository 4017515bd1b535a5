"""The live loop: a patient presses Start on their page, their home agent records the set and reports progress.

The agent holds one outbound stream (GET /api/v1/live/agent) that carries commands to it; it posts progress
(POST /api/v1/live/progress); pages receive both through the event stream (backend/events). Nothing is stored
but the device's presence: which stream is its current one and when it was last heard from.
"""
