"""The ten DMC tasks of the ReFPO MuJoCo Playground benchmark, by suite name."""

from __future__ import annotations

from tasks.dmc.acrobot import AcrobotSwingup
from tasks.dmc.ball_in_cup import BallInCup
from tasks.dmc.cartpole import CartpoleBalance, CartpoleSwingup
from tasks.dmc.cheetah import CheetahRun
from tasks.dmc.finger import FingerSpin
from tasks.dmc.pendulum import PendulumSwingup
from tasks.dmc.point_mass import PointMass
from tasks.dmc.reacher import ReacherEasy
from tasks.dmc.walker import WalkerWalk

TASKS = {
    cls.name: cls
    for cls in (CartpoleBalance, CartpoleSwingup, PendulumSwingup, PointMass, BallInCup, FingerSpin, ReacherEasy,
                AcrobotSwingup, CheetahRun, WalkerWalk)
}  # fmt: skip
