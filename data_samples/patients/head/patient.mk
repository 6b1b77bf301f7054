# The classic quarter-resolution head CT (../shared/data/headsq, not bundled): raw values are HU + 1024.
# The tissue is everything denser than fat (skin, muscle, brain, bone) as one solid: an HU window, the
# largest component, holes filled.
CT := $(SHARED_DATA)/headsq/quarter.nhdr
IMPORT_ARGS := --rescale-intercept -1024
CELL_MM := 6.4
GRID_ARGS := --hu-min -300 --keep-largest --fill-holes
