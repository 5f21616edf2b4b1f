# Set-up and entry points. `make demo` and `make test` work on a fresh machine:
# they create .venv, install posture_id with its pinned CPU torch, then run.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: docs figures design-results universal-model universal-fifth noise-families universal-noise-model recording-widening demo test test-fast lint bench bodies models model calibration examples real-like \
        honest-verdict noise-lofo \
        real-like-models real-like-model clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# torch first, pinned, so that nothing later resolves a CUDA build from the registry.
	$(BIN)/pip install --quiet "torch==2.13.0"
	$(BIN)/pip install --quiet -e ".[dev,robots]"
	@if $(BIN)/pip list 2>/dev/null | grep -qi '^nvidia-'; then \
	  echo "error: CUDA packages were installed on a CPU set-up; see README" >&2; exit 1; fi
	# the simulator and the fit's model for 1-3 segments, compiled once here: a first
	# command compiles nothing (posture_id/cache.py, docs/performance.md)
	$(BIN)/python -m posture_id.studies.prebuild
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/posture-id demo --out demo
	@echo "demo: wrote demo/report.md (open it beside its PNGs)"

# The example recordings shipped for the demo: simulated subjects (their true parameters
# in *.truth.json) with 0.01° white sensor noise; and a lab-like file for the tutorial
# (docs/tutorials/lab_recording.py): COM only, the lab's columns, a lab's PRTS; and a
# motion-capture trial of the straight-leg subject (docs/tutorials/c3d_trial.py): C3D,
# markers with 0.3 mm noise and a gap, platform markers and an analog tilt channel; and a
# force-plate trial as a posturography system exports it (docs/tutorials/force_plate_study.py):
# tab-separated, a title line, ms, the COP in mm, a sinusoid between level stretches.
EXAMPLES := posture_id/studies/examples
examples: $(STAMP)
	$(BIN)/posture-id simulate --params $(EXAMPLES)/tip_subject.truth.json \
	  --sensor-noise-deg 0.01 --seed 1 --out $(EXAMPLES)/tip_subject.csv
	$(BIN)/posture-id simulate --body urdf/winter_1.75m_70kg_2seg.urdf \
	  --params $(EXAMPLES)/straight_leg_subject.truth.json \
	  --sensor-noise-deg 0.01 --seed 2 --out $(EXAMPLES)/straight_leg_subject.csv
	$(BIN)/python -m posture_id.studies.lab_example $(EXAMPLES)
	$(BIN)/python -m posture_id.studies.force_plate_study $(EXAMPLES)
	$(BIN)/posture-id simulate --body urdf/winter_1.75m_70kg_2seg.urdf \
	  --params $(EXAMPLES)/straight_leg_subject.truth.json --motor-noise 0.02 --seed 3 \
	  --out $(EXAMPLES)/straight_leg_subject.c3d --c3d-forward-axis=-y --frame-rate-hz 50 \
	  --analog-per-frame 2 --marker-noise-mm 0.3 --marker-gap LHIP 40 0.12 \
	  --height-m 1.75 --mass-kg 70

# The suite on every core (pytest-xdist: one worker a core, tests handed out as they end).
test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto
	$(MAKE) docs

# The documentation site (MkDocs Material; the API and command-line references are made
# from the docstrings and parsers): broken links and references fail the build.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet -f - < docs/config/mkdocs.yml

# The pictures the README and the docs' start page show (the shipped TIP example).
figures: $(STAMP)
	$(BIN)/posture-id identify $(EXAMPLES)/tip_subject.csv --out docs/images/tip_subject.json \
	  --plot docs/images/tip_subject.png
	$(BIN)/python docs/config/architecture_figure.py --out docs/images/architecture.png

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -n auto -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check posture_id tests benchmarks docs/tutorials docs/config
	$(BIN)/lint-imports

bodies: $(STAMP)
	for r in talos g1 human; do $(BIN)/posture-id body --from-robot $$r --out urdf/$${r}_tip.urdf > /dev/null; done
	$(BIN)/posture-id body --default-tip --out posture_id/bodies/data/tip_default.urdf > /dev/null
	$(BIN)/posture-id body --height-m 1.75 --mass-kg 70 --segments 2 \
	  --out posture_id/bodies/data/winter_1.75m_70kg_2seg.urdf > /dev/null
	for n in 1 3; do $(BIN)/posture-id body --height-m 1.75 --mass-kg 70 --segments $$n \
	  --out urdf/winter_1.75m_70kg_$${n}seg.urdf > /dev/null; done

# The bundled CNN models (docs/learning.md): a data set, training (under 30 min each on
# 2 cores), evaluation into docs/models/, then weights + sidecar into the package.
MODEL_TRIALS ?= 30000
MODEL_EPOCHS ?= 24
# white sensor noise on the training sway, SD drawn per trial from [0, MODEL_NOISE_DEG]°:
# the bundled models hold on noisy recordings (docs/learning.md)
MODEL_NOISE_DEG ?= 0.05
MODELS_DIR   := posture_id/learning/models
TWO_SEGMENT  := urdf/winter_1.75m_70kg_2seg.urdf

models: $(STAMP)
	$(MAKE) universal-model
	$(MAKE) model NAME=tip_default URDF=urdf/tip_default.urdf FITS=500
	$(MAKE) model NAME=winter_1.75m_70kg_2seg URDF=$(TWO_SEGMENT)

# The universal identifier (docs/universal.md): five sets (UNIVERSAL_SHARDS drawn bodies
# and PRTSs over the whole scope, PEOPLE_SHARDS of people-like sway only, 10–40 % locked,
# PRESET_SHARDS of lumped humanoids only, bent bodies, SMALL_SHARDS of small tilts,
# 0.35–1°, two fifths lumped humanoids, and ROBOT_SHARDS of robot-like bodies, the lumped
# humanoids' segments jittered ±15 %, at 0.35–1.5°; 64 parameter sets each), the network
# trained on all five under the low-pass motor noise (data/models/universal, the base that
# benchmarks/noise_lofo.py fine-tunes) and checked; then its noise stage
# (universal-noise-model), which is what is bundled. Resumable.
UNIVERSAL_SHARDS ?= 3000
PEOPLE_SHARDS    ?= 4500
PRESET_SHARDS    ?= 1200
SMALL_SHARDS     ?= 1500
ROBOT_SHARDS     ?= 900
UNIVERSAL_EPOCHS ?= 45
UNIVERSAL_DIR    := posture_id/learning/models/universal
universal-model: $(STAMP)
	$(BIN)/posture-id network universal data --out data/universal --shards $(UNIVERSAL_SHARDS) --quiet
	$(BIN)/posture-id network universal data --out data/universal_people --shards $(PEOPLE_SHARDS) \
	  --seed 1 --clean-share 0 --locked-share 0.1 0.4 --quiet
	$(BIN)/posture-id network universal data --out data/universal_presets --shards $(PRESET_SHARDS) \
	  --seed 2 --tip-share 0 --preset-share 1 --quiet
	$(BIN)/posture-id network universal data --out data/universal_small --shards $(SMALL_SHARDS) \
	  --seed 3 --amplitude-deg 0.35 1 --tip-share 0.1 --preset-share 0.4 --quiet
	$(BIN)/posture-id network universal data --out data/universal_robots --shards $(ROBOT_SHARDS) \
	  --seed 4 --amplitude-deg 0.35 1.5 --tip-share 0.05 --preset-share 0.9 \
	  --preset-jitter 0.15 --quiet
	$(BIN)/posture-id network universal train data/universal data/universal_people \
	  data/universal_presets data/universal_small data/universal_robots \
	  --out data/models/universal --epochs $(UNIVERSAL_EPOCHS) --fresh-motor-noise --quiet
	$(BIN)/posture-id network universal calibrate data/models/universal data/universal \
	  data/universal_people data/universal_presets data/universal_small \
	  data/universal_robots > /dev/null
	$(MAKE) universal-noise-model

# The first fifth of each of universal-model's five sets (the same seeds and flags, so
# the same shards): beside the noise-family set, what the noise stage
# is fine-tuned, calibrated and given its typicality reference on.
FIFTH_DIR := data/universal_fifth
universal-fifth: $(STAMP)
	$(BIN)/posture-id network universal data --out $(FIFTH_DIR)/universal --shards 600 --quiet
	$(BIN)/posture-id network universal data --out $(FIFTH_DIR)/universal_people --shards 900 \
	  --seed 1 --clean-share 0 --locked-share 0.1 0.4 --quiet
	$(BIN)/posture-id network universal data --out $(FIFTH_DIR)/universal_presets --shards 240 \
	  --seed 2 --tip-share 0 --preset-share 1 --quiet
	$(BIN)/posture-id network universal data --out $(FIFTH_DIR)/universal_small --shards 300 \
	  --seed 3 --amplitude-deg 0.35 1 --tip-share 0.1 --preset-share 0.4 --quiet
	$(BIN)/posture-id network universal data --out $(FIFTH_DIR)/universal_robots --shards 180 \
	  --seed 4 --amplitude-deg 0.35 1.5 --tip-share 0.05 --preset-share 0.9 \
	  --preset-jitter 0.15 --quiet

# The set over the six noise families (docs/real_recordings.md, "Noise of other shapes";
# 10 min here): each trial's torque and measurement noise drawn from one family.
NOISE_SHARDS ?= 900
noise-families: $(STAMP)
	$(BIN)/posture-id network universal data --out data/universal_families --shards $(NOISE_SHARDS) \
	  --seed 11 --clean-share 0.1 --locked-share 0.1 0.6 --noise-families low_pass \
	  two_corners shallow correlated drifting changing --quiet

# The bundled universal model (docs/universal.md, "Noise of other shapes" and "One model,
# two networks, chosen by the noise"): the base (data/models/universal) fine-tuned on the
# fifth sets and the noise-family set, each trial's motor noise turned to a new draw and
# its spectrum tilted by a PSD slope in ±NOISE_TILT every epoch (the noise stage,
# data/models/universal_noise); the base and the stage in one model, gated by the
# recording's noise (the base for white noise or nearly none, the stage for noise shaped
# by the body); calibrated and checked on the same sets, its typicality reference made on
# them; weights and sidecars into the package; the table over body families and stimuli
# (docs/results/universal) remade. Resumable.
NOISE_SETS   = $(FIFTH_DIR)/universal $(FIFTH_DIR)/universal_people \
               $(FIFTH_DIR)/universal_presets $(FIFTH_DIR)/universal_small \
               $(FIFTH_DIR)/universal_robots data/universal_families
NOISE_EPOCHS ?= 20
NOISE_TILT   ?= 1
GATED_DIR    := data/models/universal_gated
universal-noise-model: universal-fifth noise-families
	$(BIN)/posture-id network universal train $(NOISE_SETS) --init data/models/universal \
	  --out data/models/universal_noise --epochs $(NOISE_EPOCHS) --learning-rate 5e-4 \
	  --fresh-motor-noise --motor-noise-tilt $(NOISE_TILT) --quiet
	$(BIN)/posture-id network universal ensemble data/models/universal data/models/universal_noise \
	  --by-noise --out $(GATED_DIR)
	$(BIN)/posture-id network universal calibrate $(GATED_DIR) $(NOISE_SETS) > /dev/null
	$(BIN)/posture-id network universal typicality $(GATED_DIR) $(NOISE_SETS) > /dev/null
	mkdir -p $(UNIVERSAL_DIR) docs/models/universal
	cp $(GATED_DIR)/model.safetensors $(GATED_DIR)/model.json $(GATED_DIR)/calibration.json \
	  $(GATED_DIR)/typicality.safetensors $(UNIVERSAL_DIR)/
	cp $(GATED_DIR)/model.json $(GATED_DIR)/check.md $(GATED_DIR)/check.json \
	  $(GATED_DIR)/typicality.md $(GATED_DIR)/typicality.json docs/models/universal/
	$(BIN)/posture-id network universal table --trials 2048 --cache data/table_cells --quiet \
	  --out $(GATED_DIR)/table > /dev/null
	cp $(GATED_DIR)/table/table.json $(GATED_DIR)/table/table.md $(GATED_DIR)/table/table.png \
	  docs/results/universal/
	$(MAKE) recording-widening

# The bundled model's recording widening (docs/uncertainty.md, "People-like sway: intervals
# widened by the recording's own noise"): people-like subjects of every noise family drawn
# with another seed than the benchmark's and identified without it (the calibration), and
# the benchmark's own (the check); fitted, checked family by family, written beside the
# weights (about 10 min here).
recording-widening: $(STAMP)
	rm -f $(UNIVERSAL_DIR)/widening.json
	$(BIN)/python benchmarks/honest_verdict.py --subjects 24 --groups people-like --seed 777 \
	  --out data/widening_calibration
	$(BIN)/python benchmarks/honest_verdict.py --subjects 24 --groups people-like \
	  --out data/widening_check
	$(BIN)/python -m posture_id.studies.widening data/widening_calibration/rows.json \
	  --model $(UNIVERSAL_DIR) --check data/widening_check/rows.json \
	  --out docs/results/widening/report.md

model: $(STAMP)
	$(BIN)/posture-id network cnn data generate --trials $(MODEL_TRIALS) --body $(URDF) \
	  --sensor-noise-deg $(MODEL_NOISE_DEG) --out data/$(NAME) --quiet
	$(BIN)/posture-id network cnn train data/$(NAME) --out data/models/$(NAME) --epochs $(MODEL_EPOCHS) \
	  --quiet
	$(BIN)/posture-id network cnn evaluate data/models/$(NAME) data/$(NAME) --out docs/models/$(NAME)
	$(BIN)/posture-id network cnn calibrate data/models/$(NAME) data/$(NAME) \
	  --out docs/models/$(NAME)/calibration --fits $(FITS) --install > /dev/null
	mkdir -p $(MODELS_DIR)/$(NAME)
	cp data/models/$(NAME)/model.json data/models/$(NAME)/log.jsonl \
	  data/models/$(NAME)/loss.png docs/models/$(NAME)/
	cp data/models/$(NAME)/model.safetensors data/models/$(NAME)/model.json \
	  data/models/$(NAME)/calibration.json $(MODELS_DIR)/$(NAME)/

# The intervals (docs/uncertainty.md): the CNN's conformal calibration on the validation
# split and its check on the test split; for the TIP also least squares refining the CNN's
# answers on FITS test trials per noise level (about 1 h on 2 cores, resumable).
FITS ?= 0
calibration: $(STAMP)
	$(BIN)/posture-id network cnn calibrate data/models/tip_default data/tip_default \
	  --out docs/models/tip_default/calibration --fits 500 --install > /dev/null
	$(BIN)/posture-id network cnn calibrate data/models/$(notdir $(TWO_SEGMENT:.urdf=)) \
	  data/$(notdir $(TWO_SEGMENT:.urdf=)) \
	  --out docs/models/$(notdir $(TWO_SEGMENT:.urdf=))/calibration --install > /dev/null
	cp data/models/tip_default/calibration.json $(MODELS_DIR)/tip_default/
	cp data/models/$(notdir $(TWO_SEGMENT:.urdf=))/calibration.json \
	  $(MODELS_DIR)/$(notdir $(TWO_SEGMENT:.urdf=))/

# People-like subjects (docs/real_recordings.md): per PRTS, a data set with motor noise
# (level drawn per trial from [0, 0.8]°) and 0.05° sensor noise, a spectrogram CNN and an
# FRF network trained on it; then the benchmark of raw-sway and locked least squares and
# the two networks, into docs/results/real_like.*.
# (36 000 trials per PRTS: docs/real_recordings.md)
REAL_TRIALS ?= 36000
real-like-models: $(STAMP)
	$(MAKE) real-like-model STATES=242 CYCLES=2 REAL_TRIALS=36000
	$(MAKE) real-like-model STATES=80 CYCLES=6 REAL_TRIALS=36000

real-like-model: $(STAMP)
	$(BIN)/posture-id network cnn data generate --trials $(REAL_TRIALS) --states $(STATES) \
	  --cycles $(CYCLES) --motor-noise 0.8 --sensor-noise-deg 0.05 --out data/real_$(STATES) --quiet
	$(BIN)/posture-id network cnn train data/real_$(STATES) --layout frf --epochs 30 \
	  --out data/models/real_$(STATES)_frf --quiet
	$(BIN)/posture-id network cnn train data/real_$(STATES) --epochs 20 --out data/models/real_$(STATES)_cnn \
	  --quiet

real-like: real-like-models
	$(BIN)/python benchmarks/why_raw_sway_fails.py
	$(BIN)/python benchmarks/real_like.py --subjects 30

# Real sway answered honestly (docs/identify.md, "Trust"; docs/real_recordings.md, "Noise
# of other shapes"): the verdict's benchmark (clean, six noise families, five mistakes),
# then the leave-one-family-out fine-tunes of the base network (resumable).
honest-verdict: $(STAMP)
	$(BIN)/python benchmarks/honest_verdict.py --subjects 24 --out docs/results/honest_verdict

# The bundled recipe held out family by family (the fifth beside the family set, the tilt):
# fine-tuned once, judged on 24 subjects a family and again on 48; the stage alone, then
# gated with the base by the noise as the bundled model is; last, each gated model given
# its recording widening fitted on 24 subjects of each family it saw (another seed), as
# the bundled model's is, and judged on 48 of the family it never saw. The base is the
# bundled model's white-noise member when data/models/universal is not there.
LOFO_RECIPE = $(BIN)/python benchmarks/noise_lofo.py --set data/universal_families \
  --beside $(FIFTH_DIR)/universal $(FIFTH_DIR)/universal_people \
  $(FIFTH_DIR)/universal_presets $(FIFTH_DIR)/universal_small $(FIFTH_DIR)/universal_robots \
  --base data/models/universal --epochs 20 --learning-rate 5e-4 \
  --motor-noise-tilt $(NOISE_TILT) --models data/models/noise_lofo_recipe
noise-lofo: noise-families
	$(BIN)/python benchmarks/noise_lofo.py --set data/universal_families \
	  --base data/models/universal --epochs 20 --learning-rate 5e-4 --subjects 24 \
	  --models data/models/noise_lofo_long --out docs/results/noise_lofo
	$(BIN)/python benchmarks/noise_lofo.py --set data/universal_families \
	  --base data/models/universal --epochs 20 --learning-rate 5e-4 \
	  --motor-noise-tilt $(NOISE_TILT) --held-out shallow changing --subjects 24 \
	  --models data/models/noise_lofo_tilt --out docs/results/noise_lofo_tilt
	$(MAKE) universal-fifth
	$(LOFO_RECIPE) --subjects 24 --out docs/results/noise_lofo_recipe
	$(LOFO_RECIPE) --subjects 48 --out docs/results/noise_lofo_recipe48
	$(LOFO_RECIPE) --subjects 24 --gated --out docs/results/noise_lofo_gated
	$(LOFO_RECIPE) --subjects 48 --gated --out docs/results/noise_lofo_gated48
	$(LOFO_RECIPE) --subjects 48 --gated --widen 24 --no-bundled \
	  --out docs/results/noise_lofo_widened

# The simulator's throughput, then its kernel beside the kernel before issue 44's work
# (BENCH_BEFORE, a temporary worktree), child processes taking turns (docs/performance.md).
BENCH_BEFORE ?= 1235176
bench: $(STAMP)
	$(BIN)/python benchmarks/simulation.py
	$(BIN)/python benchmarks/simulation.py --before $(BENCH_BEFORE)

# Experiment design (docs/design.md): the Ki question under sensor noise and people-like
# sway on the TIP, then the predictions checked against least-squares fits (resumable).
design-results: $(STAMP)
	$(BIN)/posture-id design --goal ki --max-minutes 3 --max-peak-to-peak-deg 4 --draws 16 \
	  --out docs/results/design/ki_sensor --quiet > /dev/null
	$(BIN)/posture-id design --goal ki --max-minutes 3 --max-peak-to-peak-deg 4 --draws 16 \
	  --locked-share 0.3 --out docs/results/design/ki_people --quiet > /dev/null
	$(BIN)/python benchmarks/design_check.py --subjects 50 --workers 2 \
	  --body urdf/winter_1.75m_70kg_2seg.urdf --out docs/results/design

clean:
	rm -rf $(VENV) demo
