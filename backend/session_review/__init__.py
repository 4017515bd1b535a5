"""A stored session seen with the advice made from it: the service above backend.sessions and backend.suggestions.

Data flows one way: a session is stored (backend.sessions), then suggestions are made from it (backend.suggestions,
which reads the sessions' models and history). What needs both lives here: storing an upload together with its
suggestions, the session body with the suggestions its reader may see, and the therapist's dashboard (which counts
pending suggestions). backend.sessions imports nothing of either package above it (tests/test_layers.py).
"""
