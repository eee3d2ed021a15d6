#include "scene/scene.h"

namespace freqlab {

bool Scene::is_static() const {
    if (!camera.is_static()) return false;
    for (const SceneObject& o : objects)
        if (!o.animation.is_static()) return false;
    return true;
}

vec3 Scene::background(const vec3& d) const {
    for (const Light& l : lights) {
        if (l.type == LightType::Environment) return l.environment->eval(d);
        if (l.type == LightType::Sky) return l.sky.eval(d);
    }
    return vec3(0.0f);
}

}  // namespace freqlab
