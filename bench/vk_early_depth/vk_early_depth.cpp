// vk_early_depth: does a fragment shader that writes its depth keep the GPU's early depth test
// under Vulkan when it declares the direction of its write (conservative depth)?
//
// boxmarch's marching shader writes a depth never nearer than the rasterised face, so it may
// declare depth_greater. On NVIDIA's OpenGL driver 580 (H100) such a shader ran for every
// rasterised fragment, declared or not. This program asks the same of a Vulkan driver, headless:
// it draws L full-screen layers (one instanced draw, a full-screen triangle per layer, depth test
// LESS_OR_EQUAL, depth writes on), each fragment spending `iterations` rounds of a hash (the
// march's stand-in), and counts the fragment shader invocations of each frame
// (VK_QUERY_PIPELINE_STATISTIC_FRAGMENT_SHADER_INVOCATIONS_BIT, as ARB_pipeline_statistics_query
// counted on GL) and times it on the GPU (timestamp queries; median over the frames).
//
// Shader variants (the same work and the same picture; layer.frag.glsl):
//   no_depth_write        writes no depth: early depth certainly allowed (the control: what the
//                         hardware culls when nothing stops it)
//   depth_undeclared      writes gl_FragDepth = face depth + offset (SPIR-V DepthReplacing only)
//   depth_greater         the same write under layout(depth_greater) (ExecutionMode DepthGreater)
//   depth_unchanged       writes the face's own depth under layout(depth_unchanged)
//   early_fragment_tests  the offset write under layout(early_fragment_tests): the tests run
//                         before the shader, which makes the write ineffective (a diagnostic; its
//                         depth is the face's)
// Orders: front_to_back (nearest layer first: early depth can cull all but the front layer),
// back_to_front (nothing to cull: every variant must shade L layers per pixel) and
// behind_cleared_depth (depth cleared nearer than every layer, as a depth pre-pass leaves it:
// early depth can cull every fragment, and no fragment of an earlier layer is still in flight).
// The harness checks the SPIR-V's execution modes, reads the image back (the front layer, red =
// 1/255, must cover every pixel; nothing when behind the cleared depth) and reports the mean
// depth written above the visible face.
//
// Build (Debian 12: glslang-tools, libvulkan-dev, g++): bash bench/vk_early_depth/build.sh [OUT]
// writes OUT (default bench/vk_early_depth/build/): vk_early_depth, layers.vert.spv, the five
// <variant>.frag.spv and a copy of the Vulkan loader, libvulkan.so.1, which the binary looks up
// beside itself first (libstdc++ and libgcc are linked statically): OUT runs as it is elsewhere.
// Run: OUT/vk_early_depth [--size 960x540] [--layers 16] [--iterations 1024] [--budget-ms 500]
//      [--max-frames 200] [--device NAME|INDEX] [--shaders DIR] [--json PATH] [--images DIR]
// The shaders are read from the binary's folder unless --shaders names another. The device is the
// first that is not a CPU unless --device names one (by its index or part of its name: a machine
// with CPU devices only, like lavapipe's, needs --device). The Vulkan loader finds the
// driver from its ICD JSON; where it does not (NVIDIA's nvidia_icd.json outside the default
// folders, or to force one driver), set VK_DRIVER_FILES (loader 1.3.234+) and VK_ICD_FILENAMES
// (older loaders) to that file, e.g. VK_DRIVER_FILES=/usr/share/vulkan/icd.d/nvidia_icd.json; for
// Mesa lavapipe /usr/share/vulkan/icd.d/lvp_icd.x86_64.json. A driver installed without its JSON
// can be named by one written by hand: NVIDIA's reads {"file_format_version": "1.0.0", "ICD":
// {"library_path": "libGLX_nvidia.so.0", "api_version": "1.3.0"}}. Validation, where installed:
// VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation, and for its synchronization checks
// VK_LAYER_ENABLES=VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT. Each configuration runs one warm-up frame, then
// frames up to --budget-ms of GPU time (at least 3, at most --max-frames). Exit status: 0, 1 with
// a one-line message on any failure, 2 when a picture was wrong (the table and JSON still written).
#include <vulkan/vulkan.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

const char* const kVariants[] = {"no_depth_write", "depth_undeclared", "depth_greater", "depth_unchanged",
                                 "early_fragment_tests"};
const int kVariantCount = 5;
// The depth-related execution modes each variant's SPIR-V must declare (sorted SPIR-V numbers):
// 9 EarlyFragmentTests, 12 DepthReplacing, 14 DepthGreater, 16 DepthUnchanged.
const std::vector<uint32_t> kExpectedModes[] = {{}, {12}, {12, 14}, {12, 16}, {9, 12}};
const char* const kOrders[] = {"front_to_back", "back_to_front", "behind_cleared_depth"};
const int kOrderCount = 3;
const uint32_t kMinFrames = 3;

struct Options {
    uint32_t width = 960, height = 540, layers = 16, iterations = 1024, max_frames = 200;
    double budget_ms = 500;
    std::string device, shaders, json, images;
};

// The push constants both stages read (settings.glsl, included by layers.vert.glsl and layer.frag.glsl).
struct Settings {
    uint32_t layer_count, iterations, back_to_front;
    float layer_spacing;
};

struct Measurement {
    std::string variant, order, modes;
    double invocations_per_pixel = NAN, gpu_ms = NAN, depth_above_face = NAN;
    uint32_t frames = 0, wrong_pixels = 0;
    uint64_t checksum = 0;
};

[[noreturn]] void fail(const std::string& message) { throw std::runtime_error(message); }

void check(VkResult result, const char* call) {
    if (result != VK_SUCCESS) fail(std::string(call) + " failed (VkResult " + std::to_string(result) + ")");
}

// Every Vulkan object of the run, destroyed in reverse order of creation (the device last).
struct Gpu {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family = 0, timestamp_bits = 0;
    bool has_statistics = false;
    VkPhysicalDeviceProperties properties{};
    std::string driver_name, driver_info;
    std::vector<std::function<void()>> destroyers;
    ~Gpu() {
        if (device) vkDeviceWaitIdle(device);
        for (auto it = destroyers.rbegin(); it != destroyers.rend(); ++it) (*it)();
        if (device) vkDestroyDevice(device, nullptr);
        if (instance) vkDestroyInstance(instance, nullptr);
    }
};

void create_device(Gpu& gpu, const std::string& choice) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "vk_early_depth";
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo instance_info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    instance_info.pApplicationInfo = &app;
    VkResult created = vkCreateInstance(&instance_info, nullptr, &gpu.instance);
    if (created == VK_ERROR_INCOMPATIBLE_DRIVER || created == VK_ERROR_INITIALIZATION_FAILED)
        fail("no Vulkan 1.1 driver found (set VK_DRIVER_FILES and VK_ICD_FILENAMES to its ICD JSON)");
    check(created, "vkCreateInstance");
    uint32_t count = 0;
    check(vkEnumeratePhysicalDevices(gpu.instance, &count, nullptr), "vkEnumeratePhysicalDevices");
    if (count == 0) fail("no Vulkan device (set VK_DRIVER_FILES and VK_ICD_FILENAMES to its ICD JSON)");
    std::vector<VkPhysicalDevice> devices(count);
    check(vkEnumeratePhysicalDevices(gpu.instance, &count, devices.data()), "vkEnumeratePhysicalDevices");
    // A machine with a GPU may list Mesa's CPU driver first: take the first real device by default,
    // and refuse to fall back to a CPU one unasked (a GPU run would time software rendering).
    // --device 1 names the second device, even where the first one's name holds a "1" (H100).
    bool by_index = !choice.empty() && choice.find_first_not_of("0123456789") == std::string::npos;
    int chosen = -1;
    for (uint32_t i = 0; i < count; ++i) {
        VkPhysicalDeviceProperties properties;
        vkGetPhysicalDeviceProperties(devices[i], &properties);
        std::printf("device %u: %s\n", i, properties.deviceName);
        bool named = by_index ? choice == std::to_string(i)
                              : !choice.empty() && std::strstr(properties.deviceName, choice.c_str()) != nullptr;
        bool first_gpu = choice.empty() && properties.deviceType != VK_PHYSICAL_DEVICE_TYPE_CPU;
        if (chosen < 0 && (named || first_gpu)) chosen = int(i);
    }
    if (chosen < 0 && !choice.empty()) fail("no Vulkan device matches --device " + choice);
    if (chosen < 0)
        fail("only CPU Vulkan devices found (set VK_DRIVER_FILES and VK_ICD_FILENAMES to the GPU's ICD JSON, or pass "
             "--device 0 to run on the CPU)");
    gpu.physical = devices[chosen];
    vkGetPhysicalDeviceProperties(gpu.physical, &gpu.properties);
    if (gpu.properties.apiVersion < VK_API_VERSION_1_1) fail("the device supports Vulkan 1.0 only (1.1 needed)");

    uint32_t extension_count = 0;
    check(vkEnumerateDeviceExtensionProperties(gpu.physical, nullptr, &extension_count, nullptr),
          "vkEnumerateDeviceExtensionProperties");
    std::vector<VkExtensionProperties> extensions(extension_count);
    check(vkEnumerateDeviceExtensionProperties(gpu.physical, nullptr, &extension_count, extensions.data()),
          "vkEnumerateDeviceExtensionProperties");
    for (const VkExtensionProperties& extension : extensions) {
        if (std::strcmp(extension.extensionName, VK_KHR_DRIVER_PROPERTIES_EXTENSION_NAME) != 0) continue;
        VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
        VkPhysicalDeviceProperties2 properties2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &driver};
        vkGetPhysicalDeviceProperties2(gpu.physical, &properties2);
        gpu.driver_name = driver.driverName;
        gpu.driver_info = driver.driverInfo;
    }

    VkPhysicalDeviceFeatures supported{}, enabled{};
    vkGetPhysicalDeviceFeatures(gpu.physical, &supported);
    gpu.has_statistics = supported.pipelineStatisticsQuery == VK_TRUE;
    enabled.pipelineStatisticsQuery = supported.pipelineStatisticsQuery;

    uint32_t family_count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(gpu.physical, &family_count, nullptr);
    std::vector<VkQueueFamilyProperties> families(family_count);
    vkGetPhysicalDeviceQueueFamilyProperties(gpu.physical, &family_count, families.data());
    gpu.queue_family = family_count;
    for (uint32_t i = 0; i < family_count && gpu.queue_family == family_count; ++i)
        if (families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) gpu.queue_family = i;
    if (gpu.queue_family == family_count) fail("the device has no graphics queue");
    gpu.timestamp_bits = families[gpu.queue_family].timestampValidBits;

    float priority = 1.0f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = gpu.queue_family;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue_info;
    device_info.pEnabledFeatures = &enabled;
    check(vkCreateDevice(gpu.physical, &device_info, nullptr, &gpu.device), "vkCreateDevice");
    vkGetDeviceQueue(gpu.device, gpu.queue_family, 0, &gpu.queue);
}

VkDeviceMemory allocate(Gpu& gpu, VkMemoryRequirements needs, VkMemoryPropertyFlags flags) {
    VkPhysicalDeviceMemoryProperties memory;
    vkGetPhysicalDeviceMemoryProperties(gpu.physical, &memory);
    for (uint32_t type = 0; type < memory.memoryTypeCount; ++type) {
        if (!(needs.memoryTypeBits & (1u << type)) || (memory.memoryTypes[type].propertyFlags & flags) != flags)
            continue;
        VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        info.allocationSize = needs.size;
        info.memoryTypeIndex = type;
        VkDeviceMemory allocation;
        check(vkAllocateMemory(gpu.device, &info, nullptr, &allocation), "vkAllocateMemory");
        VkDevice device = gpu.device;
        gpu.destroyers.push_back([=] { vkFreeMemory(device, allocation, nullptr); });
        return allocation;
    }
    fail("no suitable memory type");
}

VkImageView create_attachment(Gpu& gpu, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect,
                              const Options& options, VkImage& image) {
    VkFormatProperties support;
    vkGetPhysicalDeviceFormatProperties(gpu.physical, format, &support);
    VkFormatFeatureFlags wanted = aspect == VK_IMAGE_ASPECT_DEPTH_BIT ? VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT
                                                                      : VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT;
    if (!(support.optimalTilingFeatures & wanted)) fail("the device cannot render to format " + std::to_string(format));
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {options.width, options.height, 1};
    info.mipLevels = info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    check(vkCreateImage(gpu.device, &info, nullptr, &image), "vkCreateImage");
    VkDevice device = gpu.device;
    VkImage created = image;
    gpu.destroyers.push_back([=] { vkDestroyImage(device, created, nullptr); });
    VkMemoryRequirements needs;
    vkGetImageMemoryRequirements(gpu.device, image, &needs);
    check(vkBindImageMemory(gpu.device, image, allocate(gpu, needs, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT), 0),
          "vkBindImageMemory");
    VkImageViewCreateInfo view_info{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view_info.image = image;
    view_info.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view_info.format = format;
    view_info.subresourceRange = {aspect, 0, 1, 0, 1};
    VkImageView view;
    check(vkCreateImageView(gpu.device, &view_info, nullptr, &view), "vkCreateImageView");
    gpu.destroyers.push_back([=] { vkDestroyImageView(device, view, nullptr); });
    return view;
}

VkRenderPass create_render_pass(Gpu& gpu) {
    VkAttachmentDescription attachments[2] = {};
    VkFormat formats[2] = {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_D32_SFLOAT};
    for (int i = 0; i < 2; ++i) {
        attachments[i].format = formats[i];
        attachments[i].samples = VK_SAMPLE_COUNT_1_BIT;
        attachments[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        attachments[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        attachments[i].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        attachments[i].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[i].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        attachments[i].finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;  // read back after the last frame
    }
    VkAttachmentReference colour{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &colour;
    subpass.pDepthStencilAttachment = &depth;
    // Frames follow one another on the same attachments, and the last one is copied out.
    const VkPipelineStageFlags attachment_stages = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                                                   VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                                   VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    const VkAccessFlags attachment_writes =
            VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    VkSubpassDependency dependencies[2] = {};
    dependencies[0] = {VK_SUBPASS_EXTERNAL,
                       0,
                       attachment_stages | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       attachment_stages,
                       attachment_writes,
                       attachment_writes | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
                       0};
    dependencies[1] = {0,
                       VK_SUBPASS_EXTERNAL,
                       attachment_stages,
                       VK_PIPELINE_STAGE_TRANSFER_BIT,
                       attachment_writes,
                       VK_ACCESS_TRANSFER_READ_BIT,
                       0};
    VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    info.attachmentCount = 2;
    info.pAttachments = attachments;
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = 2;
    info.pDependencies = dependencies;
    VkRenderPass render_pass;
    check(vkCreateRenderPass(gpu.device, &info, nullptr, &render_pass), "vkCreateRenderPass");
    VkDevice device = gpu.device;
    gpu.destroyers.push_back([=] { vkDestroyRenderPass(device, render_pass, nullptr); });
    return render_pass;
}

std::vector<uint32_t> read_spirv(const std::string& path) {
    std::ifstream file(path, std::ios::binary | std::ios::ate);
    if (!file) fail("shader not found: " + path + " (run bench/vk_early_depth/build.sh, or pass --shaders DIR)");
    std::streamsize size = file.tellg();
    std::vector<uint32_t> words(size_t(size) / 4);
    file.seekg(0);
    if (size % 4 != 0 || size < 20 || !file.read(reinterpret_cast<char*>(words.data()), size) || words[0] != 0x07230203)
        fail("not a SPIR-V module: " + path);
    return words;
}

// The depth-related OpExecutionMode operands of a module (sorted): what the driver is told.
std::vector<uint32_t> depth_modes(const std::vector<uint32_t>& words) {
    std::vector<uint32_t> modes;
    for (size_t at = 5; at < words.size();) {
        uint32_t length = words[at] >> 16, opcode = words[at] & 0xffff;
        if (length == 0 || at + length > words.size()) fail("malformed SPIR-V");
        const uint32_t kOpExecutionMode = 16;
        uint32_t mode = length >= 3 ? words[at + 2] : 0;
        if (opcode == kOpExecutionMode && (mode == 9 || (mode >= 12 && mode <= 16))) modes.push_back(mode);
        at += length;
    }
    std::sort(modes.begin(), modes.end());
    return modes;
}

std::string mode_names(const std::vector<uint32_t>& modes) {
    std::string names;
    for (uint32_t mode : modes) {
        const char* name = mode == 9    ? "EarlyFragmentTests"
                           : mode == 12 ? "DepthReplacing"
                           : mode == 14 ? "DepthGreater"
                           : mode == 15 ? "DepthLess"
                                        : "DepthUnchanged";
        names += (names.empty() ? "" : " ") + std::string(name);
    }
    return names.empty() ? "none" : names;
}

VkShaderModule create_shader(Gpu& gpu, const std::vector<uint32_t>& words) {
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = words.size() * 4;
    info.pCode = words.data();
    VkShaderModule module;
    check(vkCreateShaderModule(gpu.device, &info, nullptr, &module), "vkCreateShaderModule");
    VkDevice device = gpu.device;
    gpu.destroyers.push_back([=] { vkDestroyShaderModule(device, module, nullptr); });
    return module;
}

// boxmarch's state: depth test LESS_OR_EQUAL, depth writes, no culling, no blending.
VkPipeline create_pipeline(Gpu& gpu, VkRenderPass render_pass, VkPipelineLayout layout, VkShaderModule vertex,
                           VkShaderModule fragment, const Options& options) {
    VkPipelineShaderStageCreateInfo stages[2] = {};
    stages[0] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                 nullptr,
                 0,
                 VK_SHADER_STAGE_VERTEX_BIT,
                 vertex,
                 "main"};
    stages[1] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                 nullptr,
                 0,
                 VK_SHADER_STAGE_FRAGMENT_BIT,
                 fragment,
                 "main"};
    VkPipelineVertexInputStateCreateInfo vertex_input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkViewport viewport{0, 0, float(options.width), float(options.height), 0, 1};
    VkRect2D scissor{{0, 0}, {options.width, options.height}};
    VkPipelineViewportStateCreateInfo viewports{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewports.viewportCount = viewports.scissorCount = 1;
    viewports.pViewports = &viewport;
    viewports.pScissors = &scissor;
    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = VK_CULL_MODE_NONE;
    raster.lineWidth = 1;
    VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    depth.depthTestEnable = depth.depthWriteEnable = VK_TRUE;
    depth.depthCompareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
    VkPipelineColorBlendAttachmentState blend{};
    blend.colorWriteMask =
            VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo blending{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blending.attachmentCount = 1;
    blending.pAttachments = &blend;
    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.stageCount = 2;
    info.pStages = stages;
    info.pVertexInputState = &vertex_input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewports;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pDepthStencilState = &depth;
    info.pColorBlendState = &blending;
    info.layout = layout;
    info.renderPass = render_pass;
    VkPipeline pipeline;
    check(vkCreateGraphicsPipelines(gpu.device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
          "vkCreateGraphicsPipelines");
    VkDevice device = gpu.device;
    gpu.destroyers.push_back([=] { vkDestroyPipeline(device, pipeline, nullptr); });
    return pipeline;
}

// The framebuffer, the pipelines of the five variants, the queries and the read-back buffer.
struct Scene {
    VkImage colour_image = VK_NULL_HANDLE, depth_image = VK_NULL_HANDLE;
    VkRenderPass render_pass = VK_NULL_HANDLE;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    VkPipeline pipelines[kVariantCount] = {};
    std::string modes[kVariantCount];
    VkQueryPool timestamps = VK_NULL_HANDLE, statistics = VK_NULL_HANDLE;
    VkCommandPool command_pool = VK_NULL_HANDLE;
    VkCommandBuffer commands = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;
    VkBuffer readback = VK_NULL_HANDLE;
    const uint8_t* pixels = nullptr;  // RGBA8 then float depth, width x height each
};

void create_scene(Gpu& gpu, Scene& scene, const Options& options) {
    VkDevice device = gpu.device;
    VkImageView views[2] = {create_attachment(gpu, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                                              VK_IMAGE_ASPECT_COLOR_BIT, options, scene.colour_image),
                            create_attachment(gpu, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                                              VK_IMAGE_ASPECT_DEPTH_BIT, options, scene.depth_image)};
    scene.render_pass = create_render_pass(gpu);
    VkFramebufferCreateInfo framebuffer_info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    framebuffer_info.renderPass = scene.render_pass;
    framebuffer_info.attachmentCount = 2;
    framebuffer_info.pAttachments = views;
    framebuffer_info.width = options.width;
    framebuffer_info.height = options.height;
    framebuffer_info.layers = 1;
    check(vkCreateFramebuffer(device, &framebuffer_info, nullptr, &scene.framebuffer), "vkCreateFramebuffer");
    VkFramebuffer framebuffer = scene.framebuffer;
    gpu.destroyers.push_back([=] { vkDestroyFramebuffer(device, framebuffer, nullptr); });

    VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(Settings)};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push;
    check(vkCreatePipelineLayout(device, &layout_info, nullptr, &scene.layout), "vkCreatePipelineLayout");
    VkPipelineLayout layout = scene.layout;
    gpu.destroyers.push_back([=] { vkDestroyPipelineLayout(device, layout, nullptr); });
    VkShaderModule vertex = create_shader(gpu, read_spirv(options.shaders + "/layers.vert.spv"));
    for (int variant = 0; variant < kVariantCount; ++variant) {
        std::string path = options.shaders + "/" + kVariants[variant] + ".frag.spv";
        std::vector<uint32_t> words = read_spirv(path);
        std::vector<uint32_t> modes = depth_modes(words);
        scene.modes[variant] = mode_names(modes);
        if (modes != kExpectedModes[variant])
            fail(path + " declares " + scene.modes[variant] + ", not " + mode_names(kExpectedModes[variant]));
        scene.pipelines[variant] =
                create_pipeline(gpu, scene.render_pass, scene.layout, vertex, create_shader(gpu, words), options);
    }

    VkQueryPoolCreateInfo query_info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    if (gpu.timestamp_bits > 0) {
        query_info.queryType = VK_QUERY_TYPE_TIMESTAMP;
        query_info.queryCount = 2 * options.max_frames;
        check(vkCreateQueryPool(device, &query_info, nullptr, &scene.timestamps), "vkCreateQueryPool");
        VkQueryPool pool = scene.timestamps;
        gpu.destroyers.push_back([=] { vkDestroyQueryPool(device, pool, nullptr); });
    }
    if (gpu.has_statistics) {
        query_info.queryType = VK_QUERY_TYPE_PIPELINE_STATISTICS;
        query_info.queryCount = options.max_frames;
        query_info.pipelineStatistics = VK_QUERY_PIPELINE_STATISTIC_FRAGMENT_SHADER_INVOCATIONS_BIT;
        check(vkCreateQueryPool(device, &query_info, nullptr, &scene.statistics), "vkCreateQueryPool");
        VkQueryPool pool = scene.statistics;
        gpu.destroyers.push_back([=] { vkDestroyQueryPool(device, pool, nullptr); });
    }

    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = gpu.queue_family;
    check(vkCreateCommandPool(device, &pool_info, nullptr, &scene.command_pool), "vkCreateCommandPool");
    VkCommandPool command_pool = scene.command_pool;
    gpu.destroyers.push_back([=] { vkDestroyCommandPool(device, command_pool, nullptr); });
    VkCommandBufferAllocateInfo command_info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    command_info.commandPool = scene.command_pool;
    command_info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    command_info.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(device, &command_info, &scene.commands), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(device, &fence_info, nullptr, &scene.fence), "vkCreateFence");
    VkFence fence = scene.fence;
    gpu.destroyers.push_back([=] { vkDestroyFence(device, fence, nullptr); });

    VkBufferCreateInfo buffer_info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    buffer_info.size = VkDeviceSize(options.width) * options.height * 8;
    buffer_info.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    check(vkCreateBuffer(device, &buffer_info, nullptr, &scene.readback), "vkCreateBuffer");
    VkBuffer readback = scene.readback;
    gpu.destroyers.push_back([=] { vkDestroyBuffer(device, readback, nullptr); });
    VkMemoryRequirements needs;
    vkGetBufferMemoryRequirements(device, scene.readback, &needs);
    VkDeviceMemory memory =
            allocate(gpu, needs, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    check(vkBindBufferMemory(device, scene.readback, memory, 0), "vkBindBufferMemory");
    void* mapped = nullptr;
    check(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &mapped), "vkMapMemory");
    scene.pixels = static_cast<const uint8_t*>(mapped);
}

struct Batch {
    std::vector<double> gpu_ms, invocations;
    double wall_ms = 0;
};

float layer_spacing(const Options& options) { return 1.0f / float(options.layers + 1); }

// `frames` frames of one variant in one order, one submission; the last frame's image and depth
// are copied into the read-back buffer.
Batch run_frames(Gpu& gpu, Scene& scene, int variant, int order, uint32_t frames, const Options& options) {
    VkCommandBuffer commands = scene.commands;
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(commands, &begin), "vkBeginCommandBuffer");
    if (scene.timestamps) vkCmdResetQueryPool(commands, scene.timestamps, 0, 2 * frames);
    if (scene.statistics) vkCmdResetQueryPool(commands, scene.statistics, 0, frames);
    Settings settings{options.layers, options.iterations, order == 1 ? 1u : 0u, layer_spacing(options)};
    VkClearValue clears[2] = {};
    clears[1].depthStencil.depth = order == 2 ? 0.5f * settings.layer_spacing : 1.0f;
    VkRenderPassBeginInfo pass{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    pass.renderPass = scene.render_pass;
    pass.framebuffer = scene.framebuffer;
    pass.renderArea = {{0, 0}, {options.width, options.height}};
    pass.clearValueCount = 2;
    pass.pClearValues = clears;
    for (uint32_t frame = 0; frame < frames; ++frame) {
        // Each frame waits for the one before, so its timestamps span its own work only.
        vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0,
                             nullptr, 0, nullptr, 0, nullptr);
        if (scene.timestamps)
            vkCmdWriteTimestamp(commands, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, scene.timestamps, 2 * frame);
        if (scene.statistics) vkCmdBeginQuery(commands, scene.statistics, frame, 0);
        vkCmdBeginRenderPass(commands, &pass, VK_SUBPASS_CONTENTS_INLINE);
        vkCmdBindPipeline(commands, VK_PIPELINE_BIND_POINT_GRAPHICS, scene.pipelines[variant]);
        vkCmdPushConstants(commands, scene.layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                           sizeof(settings), &settings);
        vkCmdDraw(commands, 3, options.layers, 0, 0);
        vkCmdEndRenderPass(commands);
        if (scene.statistics) vkCmdEndQuery(commands, scene.statistics, frame);
        if (scene.timestamps)
            vkCmdWriteTimestamp(commands, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, scene.timestamps, 2 * frame + 1);
    }
    VkBufferImageCopy copies[2] = {};
    copies[0].imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copies[0].imageExtent = {options.width, options.height, 1};
    copies[1] = copies[0];
    copies[1].bufferOffset = VkDeviceSize(options.width) * options.height * 4;
    copies[1].imageSubresource.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
    vkCmdCopyImageToBuffer(commands, scene.colour_image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, scene.readback, 1,
                           &copies[0]);
    vkCmdCopyImageToBuffer(commands, scene.depth_image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, scene.readback, 1,
                           &copies[1]);
    VkBufferMemoryBarrier to_host{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    to_host.srcQueueFamilyIndex = to_host.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    to_host.buffer = scene.readback;
    to_host.size = VK_WHOLE_SIZE;
    vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, nullptr, 1,
                         &to_host, 0, nullptr);
    check(vkEndCommandBuffer(commands), "vkEndCommandBuffer");

    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &commands;
    auto start = std::chrono::steady_clock::now();
    check(vkQueueSubmit(gpu.queue, 1, &submit, scene.fence), "vkQueueSubmit");
    VkResult waited = vkWaitForFences(gpu.device, 1, &scene.fence, VK_TRUE, 600ull * 1000 * 1000 * 1000);
    if (waited == VK_TIMEOUT) fail("a batch of frames ran over 600 s (lower --iterations or --size)");
    check(waited, "vkWaitForFences");
    Batch batch;
    batch.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    check(vkResetFences(gpu.device, 1, &scene.fence), "vkResetFences");

    const VkQueryResultFlags flags = VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT;
    if (scene.timestamps) {
        std::vector<uint64_t> ticks(2 * frames);
        check(vkGetQueryPoolResults(gpu.device, scene.timestamps, 0, 2 * frames, ticks.size() * 8, ticks.data(), 8,
                                    flags),
              "vkGetQueryPoolResults");
        uint64_t mask = gpu.timestamp_bits >= 64 ? ~0ull : (1ull << gpu.timestamp_bits) - 1;  // the counter wraps
        for (uint32_t frame = 0; frame < frames; ++frame)
            batch.gpu_ms.push_back(double((ticks[2 * frame + 1] - ticks[2 * frame]) & mask) *
                                   gpu.properties.limits.timestampPeriod * 1e-6);
    }
    if (scene.statistics) {
        std::vector<uint64_t> counts(frames);
        check(vkGetQueryPoolResults(gpu.device, scene.statistics, 0, frames, counts.size() * 8, counts.data(), 8,
                                    flags),
              "vkGetQueryPoolResults");
        batch.invocations.assign(counts.begin(), counts.end());
    }
    return batch;
}

double median(std::vector<double> values) {
    if (values.empty()) return NAN;
    std::sort(values.begin(), values.end());
    size_t middle = values.size() / 2;
    return values.size() % 2 ? values[middle] : 0.5 * (values[middle - 1] + values[middle]);
}

void write_ppm(const std::string& path, const uint8_t* rgba, const Options& options) {
    std::ofstream file(path, std::ios::binary);
    file << "P6\n" << options.width << " " << options.height << "\n255\n";
    for (size_t pixel = 0; pixel < size_t(options.width) * options.height; ++pixel)
        file.write(reinterpret_cast<const char*>(rgba + 4 * pixel), 3);
    if (!file) fail("cannot write " + path);
}

// One warm-up frame (it pays for any lazy compilation), then frames up to the budget.
Measurement measure(Gpu& gpu, Scene& scene, int variant, int order, const Options& options) {
    Batch warm = run_frames(gpu, scene, variant, order, 1, options);
    double frame_ms = scene.timestamps ? warm.gpu_ms[0] : warm.wall_ms;
    double wanted = std::ceil(options.budget_ms / std::max(frame_ms, 1e-6));
    uint32_t frames = uint32_t(std::min<double>(options.max_frames, std::max<double>(kMinFrames, wanted)));
    Batch batch = run_frames(gpu, scene, variant, order, frames, options);

    Measurement result;
    result.variant = kVariants[variant];
    result.order = kOrders[order];
    result.modes = scene.modes[variant];
    result.frames = frames;
    double pixel_count = double(options.width) * options.height;
    result.gpu_ms = median(batch.gpu_ms);
    result.invocations_per_pixel = median(batch.invocations) / pixel_count;
    // The front layer (red 1/255) must cover every pixel; behind the cleared depth nothing may be drawn.
    const uint8_t expected_red = order == 2 ? 0 : 1;
    const float* depth = reinterpret_cast<const float*>(scene.pixels + size_t(pixel_count) * 4);
    float visible_depth = order == 2 ? 0.5f * layer_spacing(options) : layer_spacing(options);
    double depth_above = 0;
    result.checksum = 1469598103934665603ull;  // FNV-1a over the RGBA bytes
    for (size_t pixel = 0; pixel < size_t(pixel_count); ++pixel) {
        result.wrong_pixels += scene.pixels[4 * pixel] != expected_red;
        depth_above += depth[pixel] - visible_depth;
        for (int byte = 0; byte < 4; ++byte)
            result.checksum = (result.checksum ^ scene.pixels[4 * pixel + byte]) * 1099511628211ull;
    }
    result.depth_above_face = depth_above / pixel_count / layer_spacing(options);
    if (!options.images.empty())
        write_ppm(options.images + "/" + result.variant + "_" + result.order + ".ppm", scene.pixels, options);
    return result;
}

double ratio(double value, double control) { return control > 0 ? value / control : NAN; }

std::string json_number(double value) {
    if (!std::isfinite(value)) return "null";  // strict JSON: an unmeasured or undefined figure is null
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", value);
    return text;
}

std::string json_string(const std::string& text) {
    std::string quoted = "\"";
    for (unsigned char c : text) {
        if (c == '"' || c == '\\') quoted += '\\';
        if (c < 0x20) {
            char escaped[8];
            std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
            quoted += escaped;
        } else {
            quoted += char(c);
        }
    }
    return quoted + "\"";
}

std::string version_text(uint32_t version, bool nvidia) {
    // NVIDIA packs its driver version as 10.8.8.6 bits; the API and Mesa as VK_MAKE_API_VERSION.
    uint32_t parts[3] = {version >> 22, (version >> 12) & 0x3ff, version & 0xfff};
    if (nvidia) parts[1] = (version >> 14) & 0xff, parts[2] = (version >> 6) & 0xff;
    return std::to_string(parts[0]) + "." + std::to_string(parts[1]) + "." + std::to_string(parts[2]);
}

void write_json(const std::string& path, const Gpu& gpu, const Options& options,
                const std::vector<std::vector<Measurement>>& results) {
    const VkPhysicalDeviceProperties& device = gpu.properties;
    std::string json =
            "{\n  \"device\": {\"name\": " + json_string(device.deviceName) +
            ", \"type\": " + std::to_string(device.deviceType) + ", \"vendor_id\": " + std::to_string(device.vendorID) +
            ", \"device_id\": " + std::to_string(device.deviceID) +
            ", \"api_version\": " + json_string(version_text(device.apiVersion, false)) +
            ", \"driver_version\": " + json_string(version_text(device.driverVersion, device.vendorID == 0x10de)) +
            ", \"driver_version_raw\": " + std::to_string(device.driverVersion) +
            ", \"driver_name\": " + json_string(gpu.driver_name) +
            ", \"driver_info\": " + json_string(gpu.driver_info) + "},\n";
    json += "  \"settings\": {\"width\": " + std::to_string(options.width) +
            ", \"height\": " + std::to_string(options.height) + ", \"layers\": " + std::to_string(options.layers) +
            ", \"iterations\": " + std::to_string(options.iterations) +
            ", \"budget_ms\": " + json_number(options.budget_ms) +
            ", \"max_frames\": " + std::to_string(options.max_frames) + "},\n";
    json += std::string("  \"pipeline_statistics\": ") + (gpu.has_statistics ? "true" : "false") +
            ", \"timestamps\": " + (gpu.timestamp_bits > 0 ? "true" : "false") +
            ", \"timestamp_period_ns\": " + json_number(device.limits.timestampPeriod) + ",\n  \"results\": [";
    const char* separator = "\n";
    for (const std::vector<Measurement>& order : results) {
        for (size_t variant = 0; variant < order.size(); ++variant) {
            const Measurement &m = order[variant], &all = results[1][variant];  // all: back to front
            json += separator;
            separator = ",\n";
            json += "    {\"variant\": " + json_string(m.variant) + ", \"order\": " + json_string(m.order) +
                    ", \"execution_modes\": " + json_string(m.modes) + ", \"frames\": " + std::to_string(m.frames) +
                    ", \"invocations_per_pixel\": " + json_number(m.invocations_per_pixel) +
                    ", \"invocations_vs_no_depth_write\": " +
                    json_number(ratio(m.invocations_per_pixel, order[0].invocations_per_pixel)) +
                    ", \"gpu_ms_median\": " + json_number(m.gpu_ms) +
                    ", \"gpu_ms_vs_no_depth_write\": " + json_number(ratio(m.gpu_ms, order[0].gpu_ms)) +
                    ", \"invocations_vs_back_to_front\": " +
                    json_number(ratio(m.invocations_per_pixel, all.invocations_per_pixel)) +
                    ", \"gpu_ms_vs_back_to_front\": " + json_number(ratio(m.gpu_ms, all.gpu_ms)) +
                    ", \"depth_above_face_in_layer_gaps\": " + json_number(m.depth_above_face) +
                    ", \"wrong_pixels\": " + std::to_string(m.wrong_pixels) +
                    ", \"image_fnv1a\": " + json_string(std::to_string(m.checksum)) + "}";
        }
    }
    json += "\n  ]\n}\n";
    // Written whole or not at all: a failed write leaves no half file under the name asked for.
    std::string partial = path + ".partial";
    std::ofstream file(partial, std::ios::binary);
    file << json;
    file.close();
    if (!file || std::rename(partial.c_str(), path.c_str()) != 0) {
        std::remove(partial.c_str());
        fail("cannot write " + path);
    }
}

void print_table(const Gpu& gpu, const Options& options, const std::vector<std::vector<Measurement>>& results) {
    std::printf("%s (driver %s %s), Vulkan %s; %u x %u, %u layers, %u iterations\n", gpu.properties.deviceName,
                gpu.driver_name.c_str(), gpu.driver_info.c_str(),
                version_text(gpu.properties.apiVersion, false).c_str(), options.width, options.height, options.layers,
                options.iterations);
    if (!gpu.has_statistics) std::printf("fragment invocations: unsupported (no pipelineStatisticsQuery)\n");
    if (gpu.timestamp_bits == 0) std::printf("GPU time: unsupported (no timestamps on the graphics queue)\n");
    std::printf("%-21s %-21s %10s %7s %9s %7s %9s %7s  %s\n", "variant", "order", "invoc/px", "x ctrl", "GPU ms",
                "x ctrl", "depth+", "frames", "picture");
    for (const std::vector<Measurement>& order : results) {
        for (const Measurement& m : order) {
            std::printf("%-21s %-21s %10.3f %7.3f %9.4f %7.3f %9.3f %7u  %s\n", m.variant.c_str(), m.order.c_str(),
                        m.invocations_per_pixel, ratio(m.invocations_per_pixel, order[0].invocations_per_pixel),
                        m.gpu_ms, ratio(m.gpu_ms, order[0].gpu_ms), m.depth_above_face, m.frames,
                        m.wrong_pixels ? (std::to_string(m.wrong_pixels) + " px wrong").c_str() : "ok");
        }
    }
    std::printf(
            "invoc/px: fragment shader invocations counted per pixel (a GPU counts the layers it shades); x ctrl:\n"
            "against no_depth_write in the same order; depth+: mean depth written above the visible face, in gaps\n"
            "between layers.\n");
    // Where early depth works, the fragments behind the cleared depth are neither shaded nor (on a
    // GPU) counted; a driver that counts before its own early test shows it in the time alone.
    std::printf("behind the cleared depth, against the same variant back to front (1.000 where nothing is culled):\n");
    for (int variant = 0; variant < kVariantCount; ++variant) {
        const Measurement &hidden = results[2][variant], &all = results[1][variant];
        std::printf("  %-21s invocations %6.3f x, GPU ms %6.3f x\n", kVariants[variant],
                    ratio(hidden.invocations_per_pixel, all.invocations_per_pixel), ratio(hidden.gpu_ms, all.gpu_ms));
    }
}

uint32_t parse_count(const std::string& text, const char* name, uint32_t lowest, uint32_t highest) {
    char* end = nullptr;
    unsigned long value = std::strtoul(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || text[0] == '-' || value < lowest || value > highest)
        fail(std::string(name) + " must be a whole number from " + std::to_string(lowest) + " to " +
             std::to_string(highest) + ", not '" + text + "'");
    return uint32_t(value);
}

Options parse_options(int argc, char** argv) {
    Options options;
    for (int at = 1; at < argc; ++at) {
        std::string flag = argv[at];
        if (flag == "--help") {
            std::printf(
                    "usage: vk_early_depth [--size WxH] [--layers N] [--iterations K] [--budget-ms MS]\n"
                    "       [--max-frames N] [--device NAME|INDEX] [--shaders DIR] [--json PATH] [--images DIR]\n"
                    "(the source's top comment says what it measures)\n");
            std::exit(0);
        }
        if (at + 1 >= argc) fail(flag + " needs a value (--help lists the options)");
        std::string value = argv[++at];
        if (flag == "--size") {
            size_t x = value.find('x');
            if (x == std::string::npos) fail("--size must be WxH, not '" + value + "'");
            options.width = parse_count(value.substr(0, x), "--size width", 1, 16384);
            options.height = parse_count(value.substr(x + 1), "--size height", 1, 16384);
        } else if (flag == "--layers") {
            options.layers = parse_count(value, flag.c_str(), 1, 254);  // red names layer + 1 in 8 bits
        } else if (flag == "--iterations") {
            options.iterations = parse_count(value, flag.c_str(), 1, 16384);  // keeps the shader's sum exact
        } else if (flag == "--budget-ms") {
            options.budget_ms = parse_count(value, flag.c_str(), 1, 60000);
        } else if (flag == "--max-frames") {
            options.max_frames = parse_count(value, flag.c_str(), 1, 1000);
        } else if (flag == "--device") {
            options.device = value;
        } else if (flag == "--shaders") {
            options.shaders = value;
        } else if (flag == "--json") {
            options.json = value;
        } else if (flag == "--images") {
            options.images = value;
        } else {
            fail("unknown option " + flag + " (--help lists the options)");
        }
    }
    if (options.shaders.empty()) {  // the folder of this binary, where build.sh puts the SPIR-V
        char path[4096];
        ssize_t length = readlink("/proc/self/exe", path, sizeof(path) - 1);
        if (length <= 0) fail("cannot find the binary's folder: pass --shaders DIR");
        std::string binary(path, size_t(length));
        options.shaders = binary.substr(0, binary.rfind('/'));
    }
    return options;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        Options options = parse_options(argc, argv);
        Gpu gpu;
        create_device(gpu, options.device);
        Scene scene;
        create_scene(gpu, scene, options);
        std::vector<std::vector<Measurement>> results(kOrderCount);
        for (int order = 0; order < kOrderCount; ++order)
            for (int variant = 0; variant < kVariantCount; ++variant)
                results[order].push_back(measure(gpu, scene, variant, order, options));
        print_table(gpu, options, results);
        if (!options.json.empty()) write_json(options.json, gpu, options, results);
        uint32_t wrong_runs = 0;
        for (const std::vector<Measurement>& order : results)
            for (const Measurement& m : order) wrong_runs += m.wrong_pixels > 0;
        if (wrong_runs) {
            std::fprintf(stderr, "vk_early_depth: the picture was wrong in %u runs (see the table)\n", wrong_runs);
            return 2;
        }
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "vk_early_depth: %s\n", error.what());
        return 1;
    }
}
