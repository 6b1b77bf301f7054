# Two organs in contact: the right kidney and the liver of the upper-abdomen sample (../shared/data/abdomen,
# not bundled: set SHARED_DATA when it lives elsewhere), labels 2 and 5 of its 117-class label volume on the
# CT's own 3 mm grid. They touch over about 500 mm^2 (54 voxel faces) at the hepatorenal recess.
CT := $(SHARED_DATA)/abdomen/upper_abdomen_ct.nii.gz
MASK := $(SHARED_DATA)/abdomen/upper_abdomen_labels.nii.gz
CELL_MM := 3
GRID_ARGS := --labels 2,5 --label-names 2=kidney_right,5=liver --keep-largest --fill-holes
TETMESH_ARGS := --cell-size 8
SCENARIOS := ../../scenarios/abdomen_contact.yaml
