/* scene_keys_undef.h — every row macro of the key table (src/scene/scene_keys.h)
 * undefined: src/scene/scene.h after generating its structs, so that no includer
 * sees them, and src/scene/scene_keys_none.h before defining them empty. No
 * include guard. */
#undef ENTRY
#undef END_ENTRY
#undef SECTION
#undef END_SECTION
#undef KF
#undef KE
#undef KU
#undef KS
#undef KV
#undef KL
#undef EKF
#undef EKE
#undef EKU
#undef EKS
#undef EKV
