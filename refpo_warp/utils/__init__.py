"""Shared utilities (the base layer): error types, option rules, devices and Warp set-up, atomic files, console output,
timing, rsl-rl-lib version differences. Nothing here imports the rest of the project."""
