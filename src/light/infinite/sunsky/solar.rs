//! Where the sun is: its direction from a place on Earth and a UTC date and time.
//!
//! The equations are those of NOAA's Solar Calculator spreadsheet (NOAA Global Monitoring
//! Laboratory, "General Solar Position Calculations" / NOAA_Solar_Calculations_day.xls), which
//! follow J. Meeus, *Astronomical Algorithms* (2nd ed., 1998), chapters 7 (Julian day), 25 (solar
//! coordinates, low accuracy) and 28 (equation of time), for the years 1800-2100 that NOAA gives
//! them for; UT stands in for TT (Delta T is ignored). Against NREL's SPA they agree to better
//! than 0.01 degree (tests/lights_sunsky.rs). Azimuth
//! uses the atan2 form of Meeus (13.5), which stays finite at the poles where the spreadsheet's
//! acos form divides by cos(latitude) = 0.
//!
//! Frame: +Y up, -Z north, +X east (right-handed, so +Z is south).

use glam::Vec3;

use crate::light::LightError;

/// Years the NOAA equations are stated for.
pub const YEAR_RANGE: (i32, i32) = (1800, 2100);

/// A date and time in UTC (proleptic Gregorian calendar).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UtcDateTime {
    /// Year, within [`YEAR_RANGE`] when made by [`Self::new`].
    pub year: i32,
    /// 1..=12.
    pub month: u32,
    /// 1..=days in the month.
    pub day: u32,
    /// 0..=23.
    pub hour: u32,
    /// 0..=59.
    pub minute: u32,
    /// [0, 60] (60 for a leap second).
    pub second: f64,
}

fn bad(msg: String) -> LightError {
    LightError::Invalid { light: "SunSkyLight", msg }
}

fn days_in_month(year: i32, month: u32) -> u32 {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    match month {
        2 if leap => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

impl UtcDateTime {
    /// A checked date and time: each field in range, the year in [`YEAR_RANGE`].
    pub fn new(year: i32, month: u32, day: u32, hour: u32, minute: u32, second: f64) -> Result<Self, LightError> {
        if !(YEAR_RANGE.0..=YEAR_RANGE.1).contains(&year) {
            return Err(bad(format!(
                "year {year} is outside {}..={}, where the NOAA solar position holds",
                YEAR_RANGE.0, YEAR_RANGE.1
            )));
        }
        if !(1..=12).contains(&month) {
            return Err(bad(format!("month {month} must be 1..=12")));
        }
        let dim = days_in_month(year, month);
        if !(1..=dim).contains(&day) {
            return Err(bad(format!("day {day} must be 1..={dim} in {year}-{month:02}")));
        }
        if hour > 23 || minute > 59 || !(0.0..=60.0).contains(&second) {
            return Err(bad(format!("time {hour:02}:{minute:02}:{second} must be within 00:00:00..23:59:60")));
        }
        Ok(Self { year, month, day, hour, minute, second })
    }

    /// Parses `YYYY-MM-DDTHH:MM`, optionally with `:SS` (seconds, may have a fraction) and a
    /// trailing `Z`; the time is UTC. A space may stand for the `T`.
    pub fn parse(s: &str) -> Result<Self, LightError> {
        let form = || bad(format!("'{s}' is not a UTC date-time YYYY-MM-DDTHH:MM[:SS]"));
        let t = s.trim().trim_end_matches(['Z', 'z']);
        let (date, time) = t.split_once(['T', 't', ' ']).ok_or_else(form)?;
        let d: Vec<&str> = date.split('-').collect();
        let c: Vec<&str> = time.split(':').collect();
        let num = |v: &str| -> Result<u32, LightError> {
            if v.is_empty() || !v.bytes().all(|b| b.is_ascii_digit()) {
                return Err(form());
            }
            v.parse().map_err(|_| form())
        };
        let (&[y, mo, da], &[h, mi, ref rest @ ..]) = (&d[..], &c[..]) else { return Err(form()) };
        if y.len() != 4 || mo.len() != 2 || da.len() != 2 || h.len() != 2 || mi.len() != 2 || rest.len() > 1 {
            return Err(form());
        }
        let second = match rest.first() {
            Some(sec) if !sec.is_empty() && sec.bytes().all(|b| b.is_ascii_digit() || b == b'.') => {
                sec.parse::<f64>().map_err(|_| form())?
            }
            Some(_) => return Err(form()),
            None => 0.0,
        };
        Self::new(num(y)? as i32, num(mo)?, num(da)?, num(h)?, num(mi)?, second)
    }

    /// Julian day (UT) of this instant (Meeus 7.1).
    pub fn julian_day(&self) -> f64 {
        let (mut y, mut m) = (self.year as f64, self.month as f64);
        if m <= 2.0 {
            y -= 1.0;
            m += 12.0;
        }
        let a = (y / 100.0).floor();
        let b = 2.0 - a + (a / 4.0).floor();
        let day_fraction = (self.hour as f64 + (self.minute as f64 + self.second / 60.0) / 60.0) / 24.0;
        (365.25 * (y + 4716.0)).floor() + (30.6001 * (m + 1.0)).floor() + self.day as f64 + b - 1524.5 + day_fraction
    }

    /// Minutes since midnight UTC.
    fn minutes_of_day(&self) -> f64 {
        self.hour as f64 * 60.0 + self.minute as f64 + self.second / 60.0
    }
}

/// The sun seen from a place at an instant, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolarPosition {
    /// Geometric elevation above the horizon (no refraction), degrees in [-90, 90].
    pub elevation_deg: f64,
    /// Elevation corrected for atmospheric refraction (NOAA's approximation), degrees.
    pub apparent_elevation_deg: f64,
    /// Azimuth clockwise from north (90 = east), degrees in [0, 360).
    pub azimuth_deg: f64,
    /// Declination of the sun, degrees.
    pub declination_deg: f64,
    /// Equation of time, minutes (apparent minus mean solar time).
    pub equation_of_time_min: f64,
}

/// The sun's position at latitude `lat_deg` (north positive, [-90, 90]) and longitude `lon_deg`
/// (east positive, [-180, 180]) at `time` (NOAA, see the module docs).
pub fn solar_position(lat_deg: f64, lon_deg: f64, time: &UtcDateTime) -> Result<SolarPosition, LightError> {
    if !(lat_deg.is_finite() && (-90.0..=90.0).contains(&lat_deg)) {
        return Err(bad(format!("latitude {lat_deg} must be a number of degrees in [-90, 90]")));
    }
    if !(lon_deg.is_finite() && (-180.0..=180.0).contains(&lon_deg)) {
        return Err(bad(format!("longitude {lon_deg} must be a number of degrees in [-180, 180]")));
    }
    let jc = (time.julian_day() - 2_451_545.0) / 36_525.0;
    let geom_mean_long = (280.46646 + jc * (36000.76983 + jc * 0.0003032)).rem_euclid(360.0);
    let mean_anom = 357.52911 + jc * (35999.05029 - 0.0001537 * jc);
    let ecc = 0.016708634 - jc * (0.000042037 + 0.0000001267 * jc);
    let m = mean_anom.to_radians();
    let eq_ctr = m.sin() * (1.914602 - jc * (0.004817 + 0.000014 * jc))
        + (2.0 * m).sin() * (0.019993 - 0.000101 * jc)
        + (3.0 * m).sin() * 0.000289;
    let true_long = geom_mean_long + eq_ctr;
    let omega = (125.04 - 1934.136 * jc).to_radians();
    let app_long = (true_long - 0.00569 - 0.00478 * omega.sin()).to_radians();
    let mean_obliq = 23.0 + (26.0 + (21.448 - jc * (46.815 + jc * (0.00059 - jc * 0.001813))) / 60.0) / 60.0;
    let obliq = (mean_obliq + 0.00256 * omega.cos()).to_radians();
    let decl = (obliq.sin() * app_long.sin()).asin();
    let y = (obliq / 2.0).tan().powi(2);
    let l0 = geom_mean_long.to_radians();
    let eq_time = 4.0
        * (y * (2.0 * l0).sin() - 2.0 * ecc * m.sin() + 4.0 * ecc * y * m.sin() * (2.0 * l0).cos()
            - 0.5 * y * y * (4.0 * l0).sin()
            - 1.25 * ecc * ecc * (2.0 * m).sin())
        .to_degrees();
    let true_solar_time = (time.minutes_of_day() + eq_time + 4.0 * lon_deg).rem_euclid(1440.0);
    let hour_angle = (true_solar_time / 4.0 - 180.0).to_radians();
    let lat = lat_deg.to_radians();
    let sin_elev = lat.sin() * decl.sin() + lat.cos() * decl.cos() * hour_angle.cos();
    let elevation = sin_elev.clamp(-1.0, 1.0).asin().to_degrees();
    // Meeus (13.5): azimuth from south, westward; +180 turns it into from north, eastward.
    let az_south = hour_angle.sin().atan2(hour_angle.cos() * lat.sin() - decl.tan() * lat.cos());
    let azimuth = (az_south.to_degrees() + 180.0).rem_euclid(360.0);
    Ok(SolarPosition {
        elevation_deg: elevation,
        apparent_elevation_deg: elevation + refraction_deg(elevation),
        azimuth_deg: azimuth,
        declination_deg: decl.to_degrees(),
        equation_of_time_min: eq_time,
    })
}

/// Atmospheric refraction at geometric elevation `h` degrees, degrees (NOAA spreadsheet, after
/// Saemundsson / Bennett; the 85-degree cut and the low-elevation polynomial are NOAA's).
pub fn refraction_deg(h: f64) -> f64 {
    let t = h.to_radians().tan();
    let arcsec = if h > 85.0 {
        0.0
    } else if h > 5.0 {
        58.1 / t - 0.07 / t.powi(3) + 0.000086 / t.powi(5)
    } else if h > -0.575 {
        1735.0 + h * (-518.2 + h * (103.4 + h * (-12.79 + h * 0.711)))
    } else {
        -20.772 / t
    };
    arcsec / 3600.0
}

impl SolarPosition {
    /// Unit direction toward the sun at its apparent elevation, in kelvin's frame (+Y up, -Z north,
    /// +X east).
    pub fn direction(&self) -> Vec3 {
        direction_from_angles(self.apparent_elevation_deg, self.azimuth_deg)
    }
}

/// The unit direction of elevation `elevation_deg` and azimuth `azimuth_deg` (clockwise from
/// north) in kelvin's frame: +Y up, -Z north, +X east.
pub fn direction_from_angles(elevation_deg: f64, azimuth_deg: f64) -> Vec3 {
    let (se, ce) = elevation_deg.to_radians().sin_cos();
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    glam::DVec3::new(ce * sa, se, -ce * ca).normalize().as_vec3()
}
