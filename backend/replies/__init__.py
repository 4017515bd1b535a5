"""Replies to advice: the patient answers a piece of advice; the therapist reads the answers."""
