#pragma once
#include <uvr/color_map.h>
