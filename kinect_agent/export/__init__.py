"""Exports of one session that other software opens: csv (zip of tables), trc (OpenSim), bvh, fhir (R4 Bundle)."""
