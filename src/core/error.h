#pragma once
#include <uvr/error.h>
