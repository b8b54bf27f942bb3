#pragma once
// Placeholder: being written (M1 work in progress).
namespace rotolidar::bench {}
