"""The demo clinic has a patient without a Kinect whose plan she does with her own computer's camera."""

from __future__ import annotations

from sqlalchemy import func, select

from backend import demo
from backend.devices.models import Device
from backend.plans.models import Plan
from backend.users.models import User


def test_the_demo_has_a_camera_patient_with_a_plan_and_no_device(db_session):
    printed = demo.seed_demo(db_session)
    demo.seed_demo(db_session)  # a second run adds nothing
    email = demo.CAMERA_PATIENT[0]
    assert email in printed and "camera" in printed
    rows = db_session.scalars(select(User).where(User.email == email)).all()
    assert len(rows) == 1
    plans = db_session.scalars(select(Plan).where(Plan.patient_id == rows[0].id)).all()
    assert len(plans) == 1 and [i.repetitions for i in plans[0].items] == [5, 5]
    n_devices = db_session.scalar(select(func.count()).select_from(Device).where(Device.patient_id == rows[0].id))
    assert n_devices == 0
