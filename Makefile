# sphseg — the only build entry. Targets:
#   make deps    install the Debian packages the build, unit tests and tools need (when missing)
#   make deps-test  those and what the whole suite uses (ParaView's pvbatch, xvfb: tests/test_paraview.sh)
#   make         build build/sphseg with $(MPICC)
#   make run     deps, build, and the default scene inputs/shearbox_2d.yml -> out/shearbox_2d/
#   make test    unit, validation and bad-input tests; ends with "N passed, N failed"
#                (REQUIRE_GPU=1: a GPU test that skips, exit 77, fails; FAIL_FAST=1: stop at the first failure)
#   make test-mutants  plant one bug at a time in a scratch copy and run the suite on it
#                (tools/dev/mutants.py; not part of CI: half an hour to an hour on 2 cores)
#   make test-slurm  a one-node SLURM (installed and started when root): real sbatch/srun jobs (tests/test_slurm.sh)
#   make bench   particle-steps per second, CPU (tools/bench/bench.sh) and, where a GPU is visible, GPU (tools/bench/bench_gpu.sh)
# Variables a cluster user may set (e.g. from modules):
#   CC, MPICC            C compiler and MPI wrapper (mpicc)
#   PRECISION            double (default) | single
#   HDF5_DIR             prefix of a parallel HDF5 (include/, lib/); default: pkg-config hdf5-openmpi
#   CYAML_DIR            prefix of libcyaml (include/, lib/); default: system
#   METIS_DIR            prefix of METIS (include/, lib/) for Parallel:method metis; default: system
#   GPU                  1 to build the CUDA backend (default when $(NVCC) is found), 0 to skip it
#   NVCC, CUDA_ARCH      CUDA compiler and target arch for the CUDA backend (default nvcc, sm_90)
#   CUDA_HOME            CUDA toolkit prefix (default: from the location of $(NVCC))
#   OPENMP               1 (default) to thread the CPU loops with OpenMP, 0 to build without
#   PYTHON               interpreter with numpy, scipy, h5py, matplotlib (default /usr/bin/python3)

CC        ?= gcc
MPICC     ?= mpicc
NVCC      ?= nvcc
CUDA_ARCH ?= sm_90
PRECISION ?= double
OPENMP    ?= 1
PYTHON    ?= /usr/bin/python3
BUILD     ?= build

CFLAGS  ?= -O3 -march=native
override CFLAGS  += -std=c11 -D_POSIX_C_SOURCE=200809L -Wall -Wextra -Wno-unknown-pragmas -I. -Isrc
LDLIBS  := -lm

ifeq ($(PRECISION),single)
  override CFLAGS += -DSPHSEG_SINGLE
else ifneq ($(PRECISION),double)
  $(error PRECISION must be double or single, not '$(PRECISION)')
endif
ifeq ($(OPENMP),1)
  override CFLAGS  += -fopenmp
  override LDFLAGS += -fopenmp
endif

NVCC_PATH := $(shell command -v $(NVCC) 2>/dev/null)
ifeq ($(origin GPU)$(NVCC_PATH),undefined)
  $(warning $(NVCC) not found: building without the CUDA backend (--backend gpu will be refused); load a CUDA module or set NVCC= for it, or GPU=0 to silence this)
endif
GPU ?= $(if $(NVCC_PATH),1,0)
GPU_OBJ :=
ifeq ($(GPU),1)
  ifeq ($(NVCC_PATH),)
    $(error GPU=1 but $(NVCC) is not on the PATH: load a CUDA module, set NVCC=, or build with GPU=0)
  endif
  CUDA_HOME ?= $(patsubst %/bin/,%,$(dir $(NVCC_PATH)))
  NVFLAGS   ?= -O3
  override NVFLAGS   += -std=c++17 -arch=$(CUDA_ARCH) --extended-lambda -I. -Isrc -Xcompiler -Wall
  override CFLAGS    += -DSPHSEG_CUDA
  GPU_OBJ   := $(patsubst gpu/%.cu,$(BUILD)/obj/gpu/%.o,$(wildcard gpu/*.cu)) # each unit apart, no -rdc
  GPU_LIBS  := -L$(CUDA_HOME)/lib64 -Wl,-rpath,$(CUDA_HOME)/lib64 -lcudart -lstdc++
endif
ifeq ($(PRECISION),single)
  override NVFLAGS += -DSPHSEG_SINGLE
  # the single build's pair loops (gpu/gpu_pairs.cu alone) divide and take square roots at the
  # hardware's rate, within 2 ulp, denormals flushed: docs/gpu.md, "The flow pass's code"
  NVFLAGS_PAIRS ?= -prec-div=false -prec-sqrt=false -ftz=true
endif

ifdef HDF5_DIR
  HDF5_CFLAGS := -I$(HDF5_DIR)/include
  HDF5_LIBS   := -L$(HDF5_DIR)/lib -Wl,-rpath,$(HDF5_DIR)/lib -lhdf5
else
  HDF5_CFLAGS := $(shell pkg-config --cflags hdf5-openmpi 2>/dev/null || echo -I/usr/include/hdf5/openmpi)
  HDF5_LIBS   := $(shell pkg-config --libs hdf5-openmpi 2>/dev/null || echo -L/usr/lib/x86_64-linux-gnu/hdf5/openmpi -lhdf5)
endif
ifdef CYAML_DIR
  CYAML_CFLAGS := -I$(CYAML_DIR)/include
  CYAML_LIBS   := -L$(CYAML_DIR)/lib -Wl,-rpath,$(CYAML_DIR)/lib -lcyaml -lyaml
else
  CYAML_LIBS   := -lcyaml -lyaml
endif
ifdef METIS_DIR
  METIS_CFLAGS := -I$(METIS_DIR)/include
  METIS_LIBS   := -L$(METIS_DIR)/lib -Wl,-rpath,$(METIS_DIR)/lib -lmetis
else
  METIS_LIBS   := -lmetis
endif
override CFLAGS += $(HDF5_CFLAGS) $(CYAML_CFLAGS) $(METIS_CFLAGS)
LIBS   := $(HDF5_LIBS) $(CYAML_LIBS) $(METIS_LIBS) $(LDLIBS)

CORE_SRC := src/core/error.c src/core/tuning.c src/scene/scene.c src/scene/scene_yaml.c src/scene/scene_walk.c src/scene/scene_check.c src/scene/scene_write.c src/scene/scene_doc.c src/scene/scene_preset.c src/core/particles.c src/cpu/nbr.c src/cpu/nlist.c src/cpu/bound.c src/sim/setup.c src/sim/setup_container.c \
            src/cpu/backend_cpu.c src/sim/integrate.c src/output/diag.c src/output/io.c src/output/checkpoint.c \
            src/output/checkpoint_read.c src/output/checkpoint_keys.c src/output/outdir.c src/sim/stages.c src/dem/dem.c src/dem/dem_halo.c mpi/comm.c mpi/halo.c mpi/decomp.c
CORE_OBJ := $(CORE_SRC:%.c=$(BUILD)/obj/%.o)
# the driver: the command line, the settings' checks, the run loop and its log (not in the unit tests)
DRIVER_SRC := src/main.c src/settings_check.c src/run.c src/run_guard.c src/report.c
DRIVER_OBJ := $(DRIVER_SRC:%.c=$(BUILD)/obj/%.o)
HEADERS  := $(wildcard src/*.h src/*/*.h mpi/*.h)

UNIT_TESTS := test_integrate test_kernel test_nbr test_bound test_grad test_flux test_scene test_io test_io_ranks test_rates test_stress test_wall test_flow test_stab test_halo test_checkpoint test_stages test_position test_shift test_ksum test_dem
UNIT_BINS  := $(UNIT_TESTS:%=$(BUILD)/tests/%)

.PHONY: all deps deps-test run test test-slurm unit bench clean format test-mutants print-nvflags-pairs
all: $(BUILD)/sphseg

$(BUILD)/obj/%.o: %.c $(HEADERS)
	@mkdir -p $(dir $@)
	$(MPICC) $(CFLAGS) -c $< -o $@

$(BUILD)/obj/gpu/%.o: gpu/%.cu $(wildcard gpu/*.cuh) $(HEADERS)
	@mkdir -p $(dir $@)
	$(NVCC) $(NVFLAGS) $(if $(filter gpu_pairs.o,$(notdir $@)),$(NVFLAGS_PAIRS)) -c $< -o $@

# the flags gpu/gpu_pairs.cu compiles with (tools/dev/kernel_frames.py reads them)
print-nvflags-pairs:
	@echo $(NVFLAGS) $(NVFLAGS_PAIRS)

$(BUILD)/sphseg: $(DRIVER_OBJ) $(CORE_OBJ) $(GPU_OBJ)
	$(MPICC) $(LDFLAGS) $^ $(LIBS) $(GPU_LIBS) -o $@

$(BUILD)/tests/%: tests/%.c $(CORE_OBJ) $(HEADERS)
	@mkdir -p $(dir $@)
	$(MPICC) $(CFLAGS) $(LDFLAGS) $< $(CORE_OBJ) $(LIBS) -lcmocka -o $@

deps:
	@bash tools/dev/deps.sh

deps-test:
	@bash tools/dev/deps.sh --tests

run: deps all
	$(BUILD)/sphseg inputs/shearbox_2d.yml -o out/shearbox_2d --overwrite
	$(PYTHON) -m tools.analysis.shearbox_compare out/shearbox_2d

unit: $(UNIT_BINS)

test: all unit
	@PYTHON=$(PYTHON) BUILD=$(BUILD) UNIT_TESTS="$(UNIT_TESTS)" bash tests/run.sh

test-mutants:
	$(PYTHON) -m tools.dev.mutants $(MUTANTS_ARGS)

test-slurm: all
	@PYTHON=$(PYTHON) bash tests/test_slurm.sh $(BUILD)/sphseg

bench: all
	@PYTHON=$(PYTHON) bash tools/bench/bench.sh $(BUILD)/sphseg
	@if [ "$(GPU)" = 1 ] && nvidia-smi >/dev/null 2>&1; then \
	    $(MAKE) PRECISION=single BUILD=$(BUILD)-single $(BUILD)-single/sphseg >/dev/null && \
	    bash tools/bench/bench_gpu.sh $(BUILD)/bench_gpu.csv $(BUILD)/sphseg $(BUILD)-single/sphseg; \
	else echo "(no GPU visible: GPU benchmark skipped)"; fi

format:
	clang-format -i src/*.c src/*.h src/*/*.c src/*/*.h mpi/*.c mpi/*.h tests/*.c

clean:
	rm -rf $(BUILD)
