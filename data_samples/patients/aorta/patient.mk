# A vessel: the abdominal aorta of the upper-abdomen sample (../shared/data/abdomen, not bundled: set
# SHARED_DATA when it lives elsewhere), label 52 of its 117-class label volume (3 mm voxels). Its
# centerline (ctsurg-centerline: 23 points over 70 mm, radius 8.1-10.2 mm) carries the medial-atom
# vessel model (kind: vessel, sim/vessel/, docs/vessel.md); no grid, surface or tet mesh is made.
CT := $(SHARED_DATA)/abdomen/upper_abdomen_ct.nii.gz
MASK := $(SHARED_DATA)/abdomen/upper_abdomen_labels.nii.gz
CENTERLINE_ARGS := --label 52
SCENARIOS := ../../scenarios/aorta_pull.yaml ../../scenarios/aorta_clamp_cut.yaml
