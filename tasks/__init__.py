"""Task families: every subpackage is one family, found by ``refpo_warp.registry`` (nothing lists them) and imported
once; its ``__init__`` registers the family's task ids with their env cfg classes (Warp-free) and env entry points."""
