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


def test_an_exercise_without_a_movement_has_no_frames(client, make_user, auth_headers):
    r = client.get("/api/v1/exercises/deep_squat/demonstration", headers=auth_headers(make_user("patient")))
    assert r.status_code == 200, r.text
    assert r.json()["frames"] == [] and r.json()["view"] == "side"


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
