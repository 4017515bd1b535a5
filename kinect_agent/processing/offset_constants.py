"""Fitted by bench/offset_model.py (generated; do not edit): Kinect minus mocap joint offsets, metres,
body frame (x = subject's left, y = up, z = forward). See kinect_agent.processing.offset_model."""

# fmt: off
PROVENANCE: dict[str, object] = {
    "fitted_by": "bench/offset_model.py",
    "date": "2026-11-25",
    "on": "keraal",
    "data": [
        "shared/data/keraal/kinect_vicon_pairs G3 P1T1; Vicon joints by SCoRE (formats.keraal_vicon)"
    ],
    "pairs": [
        "KERAAL CTK",
        "KERAAL ELK",
        "KERAAL RTK"
    ],
    "n_pairs": 3,
    "input": "pipeline offline output (PipelineConfig defaults)",
    "validation_rmse_mm": {
        "KERAAL in-sample, fit and test on all (per_joint)": [
            75.1,
            69.0
        ],
        "UI-PRMD in-sample, fit and test on all (per_joint)": [
            97.7,
            83.5
        ],
        "KERAAL leave-one-trial-out (per_joint)": [
            75.1,
            74.9
        ],
        "UI-PRMD leave-one-movement-out (per_joint)": [
            97.7,
            92.5
        ],
        "fit KERAAL, test UI-PRMD (per_joint)": [
            97.7,
            102.3
        ],
        "fit UI-PRMD, test KERAAL (per_joint)": [
            75.1,
            85.0
        ],
        "both datasets, leave-one-trial/movement-out (per_joint)": [
            95.6,
            91.3
        ]
    }
}

OFFSETS_M: dict[str, dict[str, tuple[float, float, float]]] = {
    "all": {
        "ROOT": (0.0026, 0.0163, -0.0192),
        "NECK": (-0.0277, 0.0485, -0.0441),
        "SHO_L": (0.0097, -0.0180, 0.0331),
        "ELB_L": (0.0051, -0.0035, 0.0022),
        "WRI_L": (0.0187, -0.0191, -0.0138),
        "SHO_R": (0.0077, -0.0203, 0.0201),
        "ELB_R": (0.0092, -0.0104, 0.0016),
        "WRI_R": (0.0033, -0.0208, -0.0039),
        "HIP_L": (0.0103, 0.0374, 0.0230),
        "HIP_R": (-0.0076, 0.0242, 0.0088),
    },
}
# fmt: on
