#pragma once
#include <uvr/image.h>
