"""Seeing a policy: frames of an env's state (MuJoCo's offscreen renderer fed from the Warp state, headless through
EGL or OSMesa; a drawn grid for GridWorld), overlays and tiles, and MP4 / GIF files. Each task family draws its own
envs (``refpo_warp/tasks/<family>/render.py``); recording a policy's episodes is ``refpo_warp/evaluation/videos.py``."""
