//! Positions on a local plane: latitude and longitude (WGS-84) carried to metres north
//! and east of a first point, the tangent plane there with the ellipsoid's meridian and
//! prime-vertical radii at its latitude. Over the few kilometres of a dive the plane's
//! error is centimetres (it grows with the square of the distance over the Earth's
//! radius), far below a position fix's noise.
//! In: latitudes and longitudes, radians. Out: north and east, metres; or the first
//! point off the globe.

/// The WGS-84 ellipsoid's semi-major axis, m.
const SEMI_MAJOR_AXIS_M: f64 = 6_378_137.0;

/// The WGS-84 ellipsoid's first eccentricity squared.
const ECCENTRICITY_SQUARED: f64 = 6.694_379_990_14e-3;

/// The first of `latitude_longitude` (in degrees where `degrees`, radians otherwise)
/// that lies off the globe, and which of its two: a latitude beyond ±90°, or a
/// longitude beyond −180° to 360° (either convention, ±180° or 0° to 360°).
pub fn off_the_globe(latitude_longitude: &[[f64; 2]], degrees: bool) -> Option<(usize, usize)> {
    let to_deg = if degrees { 1.0 } else { 1f64.to_degrees() };
    latitude_longitude
        .iter()
        .enumerate()
        .find_map(|(row, &[latitude, longitude])| {
            if !((latitude * to_deg).abs() <= 90.0) {
                Some((row, 0))
            } else if !((-180.0..=360.0).contains(&(longitude * to_deg))) {
                Some((row, 1))
            } else {
                None
            }
        })
}

/// North and east of `origin` (latitude, longitude in radians) of each point of
/// `latitude_longitude_rad`, metres, on the plane tangent at `origin`.
pub fn north_east_m(origin: [f64; 2], latitude_longitude_rad: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let sin_latitude = origin[0].sin();
    let curvature = 1.0 - ECCENTRICITY_SQUARED * sin_latitude * sin_latitude;
    let meridian_m = SEMI_MAJOR_AXIS_M * (1.0 - ECCENTRICITY_SQUARED) / curvature.powf(1.5);
    let prime_vertical_m = SEMI_MAJOR_AXIS_M / curvature.sqrt();
    latitude_longitude_rad
        .iter()
        .map(|&[latitude, longitude]| {
            [
                (latitude - origin[0]) * meridian_m,
                (longitude - origin[1]) * prime_vertical_m * origin[0].cos(),
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minute of latitude at 45° is 1852.20 m (the nautical mile, 1852 m, is about its
    /// mean), of longitude there 1314.11 m, and of longitude on the equator 1855.32 m.
    #[test]
    fn a_minute_of_arc_is_a_nautical_mile() {
        let minute = (1.0f64 / 60.0).to_radians();
        let origin = [45f64.to_radians(), 0.0];
        let [north, east] = north_east_m(origin, &[[origin[0] + minute, minute]])[0];
        assert!((north - 1852.20).abs() < 0.01, "{north}");
        assert!((east - 1314.11).abs() < 0.01, "{east}");
        let [_, east] = north_east_m([0.0, 0.0], &[[0.0, minute]])[0];
        assert!((east - 1855.32).abs() < 0.01, "{east}");
    }

    /// A latitude past a pole, a longitude past either convention, and a value that is
    /// not a number are off the globe, in degrees and in radians; the edges are not.
    #[test]
    fn a_point_off_the_globe_is_found_with_its_axis() {
        let on = [[90.0, -180.0], [-90.0, 360.0], [32.8, 34.9]];
        assert_eq!(off_the_globe(&on, true), None);
        let radians: Vec<[f64; 2]> = on.iter().map(|p| p.map(f64::to_radians)).collect();
        assert_eq!(off_the_globe(&radians, false), None);
        assert_eq!(
            off_the_globe(&[[32.8, 34.9], [32.8, 500.0]], true),
            Some((1, 1))
        );
        assert_eq!(off_the_globe(&[[90.5, 0.0]], true), Some((0, 0)));
        assert_eq!(off_the_globe(&[[0.0, -3.2]], false), Some((0, 1)));
        assert_eq!(off_the_globe(&[[f64::NAN, 0.0]], true), Some((0, 0)));
    }
}
