"""A small durable job queue in the project's own database (PostgreSQL or SQLite), run by `coach-server worker`.

Why not procrastinate (a kept PostgreSQL queue): the project runs on SQLite too (the demo, one small clinic), and
a re-analysis must run there as well; the queue needs only one table, a conditional UPDATE to claim a job (with
`FOR UPDATE SKIP LOCKED` on PostgreSQL so several workers on several machines never wait on each other) and a
lease that expires, so a job of a crashed worker is taken again. Jobs are idempotent by their `key`.
"""
