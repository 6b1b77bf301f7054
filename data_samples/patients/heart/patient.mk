# The demo patient: the bundled heart CT and its whole-heart mask (data_samples/heart), with the heart
# scenarios of data_samples/scenarios. Paths are relative to this folder.
CT := ../../heart/heart_ct.nii.gz
MASK := ../../heart/heart_mask.nii.gz
# 2.4 mm cells give about the papers' 42,745-particle pig heart (48,789 particles).
CELL_MM := 2.4
GRID_ARGS := --label-names 1=heart
# Tets for the FEM scenario at 6 mm: about 3,500 nodes and 15,000 tets (the FEM paper's model sizes;
# a static Neo-Hookean frame then takes about 0.8 s). The rendered surface stays the full-resolution one.
TETMESH_ARGS := --cell-size 6
SCENARIOS := ../../scenarios/heart_grab.yaml ../../scenarios/heart_cut.yaml ../../scenarios/heart_probe.yaml \
             ../../scenarios/heart_explicit_grab.yaml ../../scenarios/heart_fem_grab.yaml \
             ../../scenarios/heart_retract.yaml ../../scenarios/heart_fem_cut.yaml \
             ../../scenarios/heart_cut_suture.yaml ../../scenarios/heart_fem_local.yaml \
             ../../scenarios/heart_fem_inclusion.yaml ../../scenarios/heart_cautery.yaml \
             ../../scenarios/heart_explicit_inclusion.yaml
