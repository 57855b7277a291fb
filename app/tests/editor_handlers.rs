//! The editor's window handlers driven with the events a window gives them (a headless
//! editor: egui, the key map, picking and the tools as in the window, frames drawn offscreen
//! on the machine's Vulkan device with the validation layer): input lands where the user saw
//! the UI, fly keys follow time, harmless no-ops and saves are said on the status line. One
//! editor (one GPU context) runs every scenario in turn. Without a Vulkan driver it skips,
//! saying so, unless VOXBRICK_REQUIRE_GPU=1 makes that a failure.

mod handlers;
mod window;

use handlers::basics::*;
use handlers::objects::*;
use handlers::selecting::*;
use handlers::session::Session;
use handlers::tools::*;

#[test]
fn the_window_handlers_take_input_as_the_user_saw_the_ui() {
    let dir = window::scratch("editor-handlers");
    let Some(mut s) = Session::start(&dir) else {
        return;
    };
    a_press_right_after_leaving_a_window_draws(&mut s);
    a_drag_pressed_on_the_sky_draws_from_where_it_meets_the_ground(&mut s);
    a_short_window_is_as_tall_as_what_it_holds(&mut s);
    a_drag_from_a_window_into_the_viewport_edits_nothing(&mut s);
    a_held_fly_key_moves_by_the_time_held(&mut s);
    a_stored_view_comes_back(&mut s);
    no_ops_and_saves_are_said_on_the_status_line(&mut s);
    a_paste_being_placed_shows_its_voxels(&mut s);
    a_dielectric_asks_for_the_bounces_it_needs(&mut s);
    selection_operations_land_and_a_selection_gets_a_material_of_its_own(&mut s);
    arrange_mode_picks_and_moves_an_object(&mut s);
    the_object_keys_and_menu_act_on_the_picked_object(&mut s);
    the_blender_key_map_is_chosen_in_the_shortcuts_window(&mut s);
    the_magic_wand_selects_with_a_click(&mut s);
    extrude_drags_a_face_and_shift_click_fills_a_plane(&mut s);
    the_stamp_puts_the_clipboard_down_along_a_drag(&mut s);
    the_colour_modes_are_chosen_in_the_tools_panel(&mut s);
    the_face_wand_and_screen_rectangles_select(&mut s);
    the_docks_leave_the_viewport_framing_fits_it_and_the_palette_paints(&mut s);
    without_a_dialog_save_as_and_open_ask_in_the_browser(&mut s, &dir);
    the_scene_exports_as_a_mesh_from_the_browser(&mut s, &dir);
    a_finished_render_is_written_while_the_editor_runs(&mut s, &dir);
    a_heightmap_becomes_a_new_terrain(&mut s, &dir);
    the_first_click_on_an_empty_scene_attaches_on_the_floor(&mut s, &dir);
    a_small_window_folds_the_docks_and_a_large_one_brings_them_back(&mut s);
    assert!(s.ed.take_errors().is_empty());
    s.ed.close().expect("a clean session");
}
