// Compiled once to build the LibTorch precompiled header shared by all torch-using targets.
