"""Motion data for SMPL humanoid tracking: the skeleton, AMASS reading, forward kinematics, the Warp motion
library (``motion_library.MotionLibrary``) and procedural AMASS-format clips. Formats and conventions:
``docs/motion.md``. Submodules are imported directly (``skeleton`` stays cheap: it pulls in no Warp).
"""
