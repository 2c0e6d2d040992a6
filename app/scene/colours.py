"""The palette of the scene, in RGB."""

EGO_BOXES = (52, 120, 246)
CAV_BOXES = (255, 140, 0)
CAV_BEFORE = (255, 185, 110)
"""Outlines of the CAV's boxes where the wrong pose puts them: a faint CAV orange."""
EGO_VEHICLE = (16, 40, 150)
CAV_VEHICLE = (190, 70, 0)
RIGHT = (30, 170, 60)
WRONG = (225, 30, 30)
MISSED = (140, 140, 140)
GHOST = (110, 110, 110)
MAP = {"lane_boundary": (185, 185, 185), "crossing": (225, 200, 120), "drivable_area": (215, 215, 215)}
MAP_OTHER = (200, 200, 200)
