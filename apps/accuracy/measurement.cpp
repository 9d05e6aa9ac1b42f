#include "measurement.h"

#include <algorithm>

#include "analytic_scenes.h"

namespace rubble::accuracy {

double median(std::vector<double> samples) {
    if (samples.empty()) return 0;
    const std::size_t mid = samples.size() / 2;
    std::nth_element(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(mid), samples.end());
    if (samples.size() % 2) return samples[mid];
    const double below = *std::max_element(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(mid));
    return 0.5 * (samples[mid] + below);
}

std::vector<MeasurementScene> measurementScenes(const std::string& scenesDir) {
    std::vector<MeasurementScene> scenes = analyticScenes();
    std::vector<MeasurementScene> reference = referenceScenes(scenesDir);
    scenes.insert(scenes.end(), std::make_move_iterator(reference.begin()), std::make_move_iterator(reference.end()));
    return scenes;
}

}  // namespace rubble::accuracy
