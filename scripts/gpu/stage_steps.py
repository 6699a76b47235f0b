#!/usr/bin/env python3
"""Derived StackNet configs for scripts/gpu/train_on_device.sh.

  stage_steps.py probe CONFIG OUT              two 2-epoch stages of 15 steps (one SimpleNet, one StackNet) with
                                               CONFIG's settings: the second epoch of each times a step
  stage_steps.py scale CONFIG OUT S_SIMPLE S_STACK BUDGET [EPOCH_OVERHEAD]
                                               CONFIG with every stage's steps scaled by one factor so that the
                                               schedule takes ~0.9 BUDGET seconds at the measured step times plus
                                               EPOCH_OVERHEAD seconds per epoch (checkpoints, loader start)

Both write `base: CONFIG` plus a `stages:` list (lists replace the base's whole). CONFIG's own `base:` chain is
resolved as stacknet/config.cpp resolves it (maps merge key by key, anything else replaces, an empty section keeps
the base's), only to read the stages.
"""
import os
import sys

import yaml


def merge(base, over):
    if isinstance(base, dict) and over is None:
        return base
    if not isinstance(base, dict) or not isinstance(over, dict):
        return over
    merged = dict(base)
    for key, value in over.items():
        merged[key] = merge(base[key], value) if key in base else value
    return merged


def load_resolved(path):
    node = yaml.safe_load(open(path)) or {}
    base = node.pop("base", None)
    if base is None:
        return node
    return merge(load_resolved(os.path.join(os.path.dirname(path), base)), node)


def batches_per_epoch(config, stage):
    """Batches of a full epoch of the stage's data (the trainer's ceil(samples / batch)), from the image files."""
    data = dict(config.get("data", {}))
    if stage.get("data"):
        data = merge(data, config["datasets"][stage["data"]])
    step = data.get("frame_step", 1)
    samples = 0
    for sequence in data.get("sequences", []):
        for folder in ("image_2", "image_0"):
            path = os.path.join(sequence, folder)
            if os.path.isdir(path):
                samples += -(-len([f for f in os.listdir(path) if f.endswith(".png")]) // step)
                break
    if samples == 0:
        sys.exit(f"error: no images in the sequences of stage {stage.get('name')} (render them first)")
    batch = config.get("train", {}).get("batch_size", 8)
    return -(-samples // batch)


def scale_stage(stage, factor, full_epoch):
    """Scales the stage's steps by `factor`. An epoch cannot be longer than its data: beyond that the epochs grow
    instead (and the learning-rate halving epochs with them), so the scaled schedule keeps its proportions."""
    epochs = stage.get("epochs", 1)
    total = max(1, round(epochs * stage["max_steps_per_epoch"] * factor))
    per_epoch = max(1, min(full_epoch, round(stage["max_steps_per_epoch"] * factor)))
    new_epochs = max(1, round(total / per_epoch))
    stage["max_steps_per_epoch"] = per_epoch
    stage["epochs"] = new_epochs
    for key in ("lr_halving_start", "lr_halving_every"):
        if stage.get(key, -1) > 0:
            stage[key] = max(1, round(stage[key] * new_epochs / epochs))


def write(config_path, out_path, stages):
    with open(out_path, "w") as out:
        yaml.safe_dump({"base": os.path.abspath(config_path), "stages": stages}, out, default_flow_style=None)


def main(argv):
    mode, config_path, out_path = argv[1:4]
    stages = load_resolved(config_path)["stages"]
    if mode == "probe":
        probe = []
        for kind in ("simple", "stack"):
            stage = dict(next(s for s in stages if s.get("model", "simple") == kind))
            # The first epoch includes start-up (CUDA context, cuDNN autotuning); the second is timed.
            stage.update(name=f"probe_{kind}", epochs=2, max_steps_per_epoch=15)
            stage.pop("lr_halving_start", None)
            stage.pop("lr_halving_every", None)
            probe.append(stage)
        write(config_path, out_path, probe)
    elif mode == "scale":
        simple_s, stack_s, budget = map(float, argv[4:7])
        epoch_overhead = float(argv[7]) if len(argv) > 7 else 0.0
        config = load_resolved(config_path)
        full_epochs = [batches_per_epoch(config, s) for s in stages]

        def step_time(s):
            return stack_s if s.get("model", "simple") == "stack" else simple_s

        def scaled(factor):
            trial = [dict(s) for s in stages]
            for s, full in zip(trial, full_epochs):
                scale_stage(s, factor, full)
            return trial

        def planned_seconds(schedule):
            return sum(s["epochs"] * (s["max_steps_per_epoch"] * step_time(s) + epoch_overhead) for s in schedule)

        # 0.9: the curve monitor beside the training is not in the probe's times. The planned time grows with the
        # factor (apart from rounding), and once an epoch reaches its data the epoch count grows with it, each epoch
        # with its overhead: bisect for the largest factor whose schedule fits, instead of solving for it.
        target = 0.9 * budget
        low, high = 0.0, 1.0
        while planned_seconds(scaled(high)) <= target and high < 1e6:
            low, high = high, 2 * high
        for _ in range(60):
            middle = (low + high) / 2
            if planned_seconds(scaled(middle)) <= target:
                low = middle
            else:
                high = middle
        factor = max(low, 1e-6)  # at the floor every stage keeps one step of one epoch
        stages = scaled(factor)
        write(config_path, out_path, stages)
        total = sum(s["epochs"] * s["max_steps_per_epoch"] for s in stages)
        print(f"steps scaled by {factor:.3f} to {total} in {sum(s['epochs'] for s in stages)} epochs "
              f"(~{planned_seconds(stages):.0f} s planned of {budget:.0f} s)")
    else:
        sys.exit(f"usage: {argv[0]} probe|scale CONFIG OUT ...")


if __name__ == "__main__":
    main(sys.argv)
