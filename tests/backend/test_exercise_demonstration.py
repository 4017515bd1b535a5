"""GET /api/v1/exercises/{slug}/demonstration: one repetition of the motion library, seen from the side or the
front, for the patient page's figure."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton


@pytest.mark.parametrize(("slug", "view", "moving", "min_travel_m"),
                         [("elbow_flexion", "side", "WRI_L", 0.3), ("shoulder_abduction", "front", "WRI_L", 0.8),
                          ("seated_knee_extension", "side", "ANK_R", 0.3)])  # fmt: skip
def test_the_demonstration_moves_the_exercise_joint_in_the_view_it_needs(
    client, make_user, auth_headers, slug, view, moving, min_travel_m
):
    r = client.get(f"/api/v1/exercises/{slug}/demonstration", headers=auth_headers(make_user("patient")))
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["view"] == view and body["joints"] == list(skeleton.JOINTS)
    frames = np.array(body["frames"])  # (T, J, 2) metres
    assert frames.shape[1:] == (len(skeleton.JOINTS), 2) and frames.shape[0] >= 2 * body["rate_hz"]
    j = skeleton.INDEX[moving]
    travel = np.ptp(frames[:, j, :], axis=0).max()
    still = np.ptp(frames[:, skeleton.INDEX["HEAD"], :], axis=0).max()
    assert travel >= min_travel_m and still < 0.1, (travel, still)
    lengths = np.linalg.norm(
        frames[:, [b for _, b in body["bones"]]] - frames[:, [a for a, _ in body["bones"]]], axis=-1
    )
    assert np.all(lengths < 0.8), "bones are body-sized (metres)"


# The UI-PRMD movements: (view, the joint that moves and how far, metres, in the view) — the right side moves.
UI_PRMD = [
    ("deep_squat", "side", "ROOT", 0.3), ("hurdle_step", "side", "KNE_R", 0.3), ("inline_lunge", "side", "ROOT", 0.2),
    ("side_lunge", "front", "ROOT", 0.2), ("standing_active_straight_leg_raise", "side", "ANK_R", 0.5),
    ("standing_shoulder_abduction", "front", "WRI_R", 0.8), ("standing_shoulder_extension", "side", "WRI_R", 0.3),
    ("standing_shoulder_rotation", "front", "WRI_R", 0.2), ("standing_shoulder_scaption", "front", "WRI_R", 0.6),
]  # fmt: skip


@pytest.mark.parametrize(("slug", "view", "moving", "min_travel_m"), UI_PRMD)
def test_a_uiprmd_movement_moves_its_joint_in_its_view_with_the_feet_on_the_floor(
    client, make_user, auth_headers, slug, view, moving, min_travel_m
):
    r = client.get(f"/api/v1/exercises/{slug}/demonstration", headers=auth_headers(make_user("patient")))
    assert r.status_code == 200, r.text
    body = r.json()
    frames = np.array(body["frames"])  # (T, J, 2) metres
    assert body["view"] == view and body["seat"] is None
    assert frames.shape[1:] == (len(skeleton.JOINTS), 2) and frames.shape[0] >= 2 * body["rate_hz"], frames.shape
    travel = np.ptp(frames[:, skeleton.INDEX[moving], :], axis=0).max()
    assert travel >= min_travel_m, f"{slug}: {moving} travels {travel:.2f} m"
    if moving.endswith("_R"):  # one-sided: the other side's same joint stays nearly still
        other = np.ptp(frames[:, skeleton.INDEX[moving[:-1] + "L"], :], axis=0).max()
        assert other < 0.15, f"{slug}: {moving[:-1]}L travels {other:.2f} m"
    ankle = frames[:, [skeleton.INDEX["ANK_L"], skeleton.INDEX["ANK_R"]], 1].min(axis=1)  # (T,) the lower ankle
    assert np.all(np.abs(ankle - ankle[0]) < 0.03), f"{slug}: a foot stays on the floor"
    assert frames[..., 1].min() > -0.02, f"{slug}: nothing goes through the floor"


def test_every_exercise_of_the_library_has_a_movement(client, make_user, auth_headers):
    headers = auth_headers(make_user("patient"))
    slugs = [e["slug"] for e in client.get("/api/v1/exercises?limit=200", headers=headers).json()["items"]]
    assert len(slugs) >= 17
    empty = [
        s for s in slugs if not client.get(f"/api/v1/exercises/{s}/demonstration", headers=headers).json()["frames"]
    ]
    assert not empty, f"no demonstration for {empty}"


def test_an_exercise_without_a_movement_has_no_frames():
    from backend.exercises.demonstration import demonstration

    assert demonstration("no_such_movement", "side").frames == []


def test_an_unknown_exercise_is_not_found(client, make_user, auth_headers):
    r = client.get("/api/v1/exercises/no_such/demonstration", headers=auth_headers(make_user("patient")))
    assert r.status_code == 404 and r.json()["error"] == "ExerciseNotFound"


@pytest.mark.parametrize(("slug", "view"), [("seated_knee_extension", "side"), ("sit_to_stand", "side"),
                                            ("elbow_flexion", "side"), ("shoulder_abduction", "front")])  # fmt: skip
def test_a_seated_exercise_has_a_chair_under_the_hips_and_a_standing_one_none(client, make_user, auth_headers, slug,
                                                                              view):  # fmt: skip
    body = client.get(f"/api/v1/exercises/{slug}/demonstration", headers=auth_headers(make_user("patient"))).json()
    first = np.array(body["frames"])[0]  # (J, 2) metres
    at = skeleton.INDEX
    if slug == "shoulder_abduction":  # done standing
        assert body["seat"] is None
        return
    seat = body["seat"]
    hips, knees = first[[at["HIP_L"], at["HIP_R"]]].mean(axis=0), first[[at["KNE_L"], at["KNE_R"]]].mean(axis=0)
    ankles = first[[at["ANK_L"], at["ANK_R"]], 1].mean()
    assert ankles < seat["height"] < hips[1], (seat, hips, ankles)  # under the hips, above the feet
    assert 0.3 < seat["height"] < 0.7, seat  # a chair's height, metres
    assert seat["x0"] < hips[0] < seat["x1"] < knees[0], (seat, hips, knees)  # from behind the hips to the knees
