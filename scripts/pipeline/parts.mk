# One large mesh baked as N jobs: each job builds one share of the octree's pages
# (mesh2svo --pages K/N), svo-merge joins the parts. make -j runs the jobs in parallel on one
# machine; an interrupted build reruns only the parts that are missing. The same commands run as
# a Slurm job array (scripts/pipeline/slurm-parts.sh) on a cluster with a shared file system.
#
#   make -f scripts/pipeline/parts.mk MESH=scan.ply OUT=out/scan PARTS=16 \
#        OPTIONS="-r 16384" LIMIT=4G -j2
#
# Files: $(OUT)/part-K-of-N.svopart per job, then $(OUT)/$(NAME).svo (the same bytes as one
# mesh2svo run with the same options, whatever PARTS).

MESH    ?= data/uv-torus.obj
OUT     ?= out/parts
BIN     ?= build/apps
PARTS   ?= 4
OPTIONS ?= -r 512
# Memory each job may use besides the mesh (mesh2svo --memory-limit); empty: no limit.
LIMIT   ?=
# Threads per job: make -j spreads the jobs over the cores instead.
THREADS ?= 1
NAME    ?= $(basename $(notdir $(MESH)))

PART_FILES := $(foreach k,$(shell seq 0 $$(($(PARTS) - 1))),$(OUT)/part-$(k)-of-$(PARTS).svopart)

.PHONY: all clean
all: $(OUT)/$(NAME).svo
clean:
	rm -rf $(OUT)

$(OUT):
	mkdir -p $@

# mesh2svo writes through a temporary and renames: a killed job leaves no part behind.
$(OUT)/part-%-of-$(PARTS).svopart: $(MESH) | $(OUT)
	$(BIN)/mesh2svo $< -o $@ $(OPTIONS) --pages $*/$(PARTS) $(if $(LIMIT),--memory-limit $(LIMIT)) \
	  -q -j $(THREADS) > $@.log

$(OUT)/$(NAME).svo: $(PART_FILES)
	$(BIN)/svo-merge $^ -o $@ -q > $(OUT)/$(NAME).merge.log
