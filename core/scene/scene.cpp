#include "scene/scene.h"

namespace freqlab {

const EnvironmentMap* Scene::environment() const {
    for (const Light& l : lights)
        if (l.environment) return l.environment.get();
    return nullptr;
}

bool Scene::is_static() const {
    if (!camera.is_static()) return false;
    for (const SceneObject& o : objects)
        if (!o.animation.is_static()) return false;
    return true;
}

vec3 Scene::background(const vec3& d) const {
    const EnvironmentMap* env = environment();
    return env ? env->eval_smooth(d) : vec3(0.0f);
}

}  // namespace freqlab
