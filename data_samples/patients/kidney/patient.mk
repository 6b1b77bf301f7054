# The right kidney of the upper-abdomen sample (../shared/data/abdomen, not bundled: set SHARED_DATA
# when it lives elsewhere): label 2 of the 117-class label volume on the CT's own 3 mm grid.
CT := $(SHARED_DATA)/abdomen/upper_abdomen_ct.nii.gz
MASK := $(SHARED_DATA)/abdomen/upper_abdomen_labels.nii.gz
CELL_MM := 3
GRID_ARGS := --labels 2 --label-names 2=kidney_right --keep-largest --fill-holes
NORMALMAP_ARGS := --size 1024
# A point force on the kidney, three models side by side (data_samples/scenarios/kidney_*.yaml).
SCENARIOS := ../../scenarios/kidney_spring_grid.yaml ../../scenarios/kidney_fem_linear.yaml \
             ../../scenarios/kidney_fem_neo_hookean.yaml ../../scenarios/kidney_fem_cautery.yaml
# The FEM paper's comparison: volume, area and displacement per model (comparison.md).
COMPARE := kidney_spring_grid.h5 kidney_fem_linear.h5 kidney_fem_neo_hookean.h5
