#pragma once
#include <uvr/system.h>
