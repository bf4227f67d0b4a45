// Precompiled header shared by every target that uses LibTorch (see cmake/CgsrTargets.cmake).
#pragma once
#include <torch/torch.h>
