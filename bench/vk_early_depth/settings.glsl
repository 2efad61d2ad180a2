// The push constants both stages read (vk_early_depth.cpp's Settings, in this order).
layout(push_constant) uniform Settings {
    uint layer_count;
    uint iterations;
    uint back_to_front;
    float layer_spacing;
} settings;
