"""Case files (``docs/formats/case-file.md``): any jointed beam assembly described in TOML,
read (:mod:`.schema`), calibrated (:mod:`.calibrate`), built (:mod:`.build`), summarized
(:mod:`.summary`) and given a nonlinear model (:mod:`.nonlinear`)."""
