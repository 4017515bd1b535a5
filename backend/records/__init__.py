"""The patient's rights over their data: everything held about them in one archive, erasure, and retention."""
