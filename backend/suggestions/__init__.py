"""The suggestions domain."""
