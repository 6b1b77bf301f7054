# The demo patient: the bundled heart CT and its whole-heart mask (data_samples/heart), with the heart
# scenarios of data_samples/scenarios. Paths are relative to this folder.
CT := ../../heart/heart_ct.nii.gz
MASK := ../../heart/heart_mask.nii.gz
# 2.4 mm cells give about the papers' 42,745-particle pig heart (48,789 particles).
CELL_MM := 2.4
GRID_ARGS := --label-names 1=heart
SCENARIOS := ../../scenarios/heart_grab.yaml ../../scenarios/heart_cut.yaml ../../scenarios/heart_probe.yaml \
             ../../scenarios/heart_explicit_grab.yaml
