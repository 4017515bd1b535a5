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
"""

from __future__ import annotations

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


def resolve(names: list[str]) -> dict[str, tuple[str, ...]]:
    """Returns, for each of our joints, the CMU joint names whose mean gives its position.

    names: the joint (and `<parent>_End`) names present in a file. A joint without any candidate is
    left out (the reader marks it not tracked).
    """
    present = set(names)
    found: dict[str, tuple[str, ...]] = {}
    for ours, candidates in CMU_TO_OURS.items():
        for cand in candidates:
            parts = tuple(cand[4:].split("+")) if cand.startswith("mid:") else (cand,)
            if all(p in present for p in parts):
                found[ours] = parts
                break
    return found
