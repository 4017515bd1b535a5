"""Device and pairing bodies."""

from __future__ import annotations

import datetime as dt

from pydantic import BaseModel, ConfigDict, Field


class PairingCodeOut(BaseModel):
    """A fresh pairing code: type it into the home agent before expires_at; it works once."""

    code: str = Field(examples=["K7QF-M2XA"])
    patient_id: int = Field(examples=[12])
    expires_at: dt.datetime


class PairIn(BaseModel):
    """The home agent exchanges a pairing code for a device token."""

    code: str = Field(min_length=4, max_length=32, examples=["K7QF-M2XA"])
    name: str = Field(default="home device", min_length=1, max_length=100, examples=["living-room Kinect"])


class PairOut(BaseModel):
    """The device token (shown once; send as `Authorization: Bearer khd_...`)."""

    device_id: int
    patient_id: int
    token: str = Field(examples=["khd_Qm9...x2"])


class DeviceOut(BaseModel):
    """A paired home device."""

    model_config = ConfigDict(from_attributes=True)
    id: int = Field(examples=[3])
    patient_id: int = Field(examples=[12])
    name: str = Field(examples=["Living-room Kinect"])
    created_at: dt.datetime = Field(examples=["2026-11-02T09:30:00Z"])
    last_seen_at: dt.datetime | None = Field(examples=["2026-11-23T08:15:00Z"])
    revoked_at: dt.datetime | None = Field(examples=[None])
