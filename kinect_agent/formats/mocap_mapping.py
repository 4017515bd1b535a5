"""Maps CMU mocap joint names (BVH/ASF conventions) to our 20-joint skeleton.

CMU names are from the subject's point of view (LeftArm = subject's left), as ours (_L = subject's
left). Each of our joints lists candidate CMU names, first present wins; `<name>_End` is the End Site
below `<name>` and `mid:<a>+<b>` the midpoint of two joints. Choices:
    ROOT  Hips (the pelvis centre, the BVH root); else the mid of LHipJoint/RHipJoint ends.
    SPINE Spine origin = end of LowerBack (lower thoracic spine, near Kinect's SPINE).
    NECK  Neck origin = base of the neck (top of Spine1, between the shoulders).
    HEAD  Head origin (top of Neck1); Kinect's HEAD is near the head centre, a few cm higher.
    SHO_*  LeftArm / RightArm origin = gleno-humeral joint (not LeftShoulder, which is the clavicle
           root at the neck base).
    ELB_*  LeftForeArm / RightForeArm origin = elbow.
    WRI_*  LeftHand / RightHand origin = wrist.
    HAN_*  LeftHandIndex1 origin (knuckles); LeftFingerBase sits at zero offset from the wrist in CMU
           conversions, so it is used only when HandIndex1 is absent, then the LeftHand end site.
    HIP_*  LeftUpLeg / RightUpLeg origin = hip joint centre (LHipJoint has a zero offset at the root).
    KNE_*  LeftLeg / RightLeg origin = knee.  ANK_*  LeftFoot / RightFoot origin = ankle.
    FOO_*  LeftToeBase / RightToeBase origin = ball of the foot; else the LeftFoot end site.
Acclaim ASF bone names (lowercase; a name is the bone's start, `<bone>_End` its end): ROOT root, SPINE end of
lowerback, NECK lowerneck (top of thorax), HEAD head (top of upperneck), SHO lhumerus, ELB lradius, WRI lhand
(ASF forearms are lradius + lwrist: lradius alone is only ~0.17 m in HDM05), HAN lfingers, HIP lfemur, KNE ltibia,
ANK lfoot, FOO ltoes.

Other sources name joints otherwise. A namespace (`mixamorig:Hips`, `Armature|Hips`) is dropped first. A joint the
CMU names do not find is then looked up by its words, side apart (`Left_Thigh`, `LeftThigh`, `Thigh_L`, `L_Thigh`,
`thigh_l` are all (L, "thigh")), in ALIASES: Mixamo and MotionBuilder (LeftUpLeg, LeftLeg, LeftArm, LeftForeArm,
Spine1 ...), Unity/VRM humanoid (LeftUpperLeg, LeftLowerLeg, LeftUpperArm, LeftLowerArm), Biovision's sample
(LeftUpArm, LeftLowArm, LeftLowLeg), Xsens MVN (LeftHip, LeftKnee, LeftAnkle, LeftShoulder = gleno-humeral joint,
LeftElbow, LeftWrist), thigh/shin/calf style. Earlier names of a list win, so a clavicle named LeftShoulder is used as
the shoulder only where no upper-arm joint exists (Xsens).
"""

from __future__ import annotations

import re

CMU_TO_OURS: dict[str, tuple[str, ...]] = {
    "ROOT": ("Hips", "mid:LHipJoint_End+RHipJoint_End", "root"),
    "SPINE": ("Spine", "LowerBack_End", "lowerback_End"),
    "NECK": ("Neck", "Spine1_End", "lowerneck"),
    "HEAD": ("Head", "Neck1_End", "head"),
    "SHO_L": ("LeftArm", "lhumerus"),
    "ELB_L": ("LeftForeArm", "lradius"),
    "WRI_L": ("LeftHand", "lhand"),
    "HAN_L": ("LeftHandIndex1", "LeftFingerBase", "LeftHand_End", "lfingers"),
    "SHO_R": ("RightArm", "rhumerus"),
    "ELB_R": ("RightForeArm", "rradius"),
    "WRI_R": ("RightHand", "rhand"),
    "HAN_R": ("RightHandIndex1", "RightFingerBase", "RightHand_End", "rfingers"),
    "HIP_L": ("LeftUpLeg", "lfemur"),
    "KNE_L": ("LeftLeg", "ltibia"),
    "ANK_L": ("LeftFoot", "lfoot"),
    "FOO_L": ("LeftToeBase", "LeftFoot_End", "ltoes"),
    "HIP_R": ("RightUpLeg", "rfemur"),
    "KNE_R": ("RightLeg", "rtibia"),
    "ANK_R": ("RightFoot", "rfoot"),
    "FOO_R": ("RightToeBase", "RightFoot_End", "rtoes"),
}


# Our joint -> candidate (side-free) word keys, first present wins; "<key>/end" is the End Site of that joint.
ALIASES: dict[str, tuple[str, ...]] = {
    "ROOT": ("hips", "pelvis", "hip"),
    "SPINE": ("spine", "chest", "spine1"),
    "NECK": ("neck", "neck1", "upperchest"),
    "HEAD": ("head",),
    "SHO": ("arm", "upperarm", "uparm", "humerus", "shoulder"),
    "ELB": ("forearm", "lowerarm", "lowarm", "elbow"),
    "WRI": ("hand", "wrist"),
    "HAN": ("handindex1", "index1", "handmiddle1", "middle1", "fingerbase", "hand/end", "wrist/end"),
    "HIP": ("upleg", "upperleg", "thigh", "hip"),
    "KNE": ("leg", "lowerleg", "lowleg", "shin", "calf", "knee"),
    "ANK": ("foot", "ankle"),
    "FOO": ("toebase", "toe", "toes", "ball", "foot/end", "ankle/end"),
}
_WORDS = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+")
_SIDES = {"left": "L", "l": "L", "right": "R", "r": "R"}


def base_name(name: str) -> str:
    """Returns a joint name without its namespace: `mixamorig:LeftArm` -> `LeftArm`, `Armature|Hips` -> `Hips`."""
    return re.split(r"[:|]", name)[-1]


def word_key(name: str) -> tuple[str, str] | None:
    """Returns (side "L", "R" or "", key) of a joint name: `Left_Thigh` -> ("L", "thigh"), `mixamorig:Spine1` ->
    ("", "spine1"), `LeftFoot_End` -> ("L", "foot/end"); None when it has no words."""
    name = base_name(name)
    end = name.endswith("_End")
    words = [w.lower() for w in _WORDS.findall(name[:-4] if end else name)]
    side = ""
    if len(words) > 1 and words[0] in _SIDES:
        side, words = _SIDES[words[0]], words[1:]
    elif len(words) > 1 and words[-1] in _SIDES:
        side, words = _SIDES[words[-1]], words[:-1]
    if not words:
        return None
    return side, "".join(words) + ("/end" if end else "")


def resolve(names: list[str]) -> dict[str, tuple[str, ...]]:
    """Returns, for each of our joints, the names (as in `names`) of the file's joints whose mean gives its position.

    names: the joint (and `<parent>_End`) names present in a file. CMU names first (namespace dropped), then ALIASES
    for the joints still missing. A joint without any candidate is left out (the reader marks it not tracked).
    """
    present: dict[str, str] = {}
    for name in names:
        present.setdefault(base_name(name), name)
    found: dict[str, tuple[str, ...]] = {}
    for ours, candidates in CMU_TO_OURS.items():
        for cand in candidates:
            parts = tuple(cand[4:].split("+")) if cand.startswith("mid:") else (cand,)
            if all(p in present for p in parts):
                found[ours] = tuple(present[p] for p in parts)
                break
    if len(found) < len(CMU_TO_OURS):
        found.update(_by_words(names, exclude=set(found)))
    return found


def _by_words(names: list[str], exclude: set[str]) -> dict[str, tuple[str, ...]]:
    """Returns {our joint: (name,)} found through ALIASES for our joints not in `exclude`."""
    keyed: dict[tuple[str, str], str] = {}
    for name in names:
        key = word_key(name)
        if key is not None:
            keyed.setdefault(key, name)
    found: dict[str, tuple[str, ...]] = {}
    for ours in CMU_TO_OURS:
        if ours in exclude:
            continue
        side = ours[-1] if ours[-2:] in ("_L", "_R") else ""
        for alias in ALIASES[ours[:3] if side else ours]:
            if (side, alias) in keyed:
                found[ours] = (keyed[(side, alias)],)
                break
    return found
