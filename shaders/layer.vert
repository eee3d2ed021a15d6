#version 330 core
// A full-screen triangle. v_uv.y = 0 at the top of the output, matching layers stored top
// row first, so the FBO holds the image the right way up for ImGui::Image.
out vec2 v_uv;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);  // (0,0) (2,0) (0,2)
    v_uv = p;
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
