//! Unit and CRS extraction from GeoTIFF keys and WKT.

use super::*;

#[test]
fn wkt2_projcrs_axis_units() {
    let wkt = br#"PROJCRS["NAD83(2011) / Oregon North (ft)",BASEGEOGCRS["NAD83(2011)",ANGLEUNIT["degree",0.0174532925199433]],CONVERSION["c",PARAMETER["False easting",8202099.738,LENGTHUNIT["foot",0.3048]]],CS[Cartesian,2],AXIS["easting (X)",east,LENGTHUNIT["US survey foot",0.304800609601219]],AXIS["northing (Y)",north,LENGTHUNIT["US survey foot",0.304800609601219]],ID["EPSG",6884]]"#;
    let info = from_wkt("LAS", wkt).expect("parses");
    assert_eq!(info.horizontal.map(|s| s.unit), Some(LengthUnit::UsSurveyFoot));
    assert_eq!(info.crs.as_deref(), Some("EPSG:6884"));
}

#[test]
fn wkt_geographic_and_garbage() {
    let info = from_wkt(
        "LAS",
        br#"GEOGCS["WGS 84",UNIT["degree",0.01745],AUTHORITY["EPSG","4326"]]"#,
    )
    .expect("ok");
    assert!(info.geographic && info.horizontal.is_none());
    assert!(from_wkt("LAS", b"PROJCS[\"x\",UNIT[").is_err());
    let deep = "A[".repeat(10_000);
    assert!(from_wkt("LAS", deep.as_bytes()).is_err());
}

#[test]
fn unit_factors() {
    assert_eq!(unit_from_factor(0.3048006096012192), Some(LengthUnit::UsSurveyFoot));
    assert_eq!(unit_from_factor(0.3048), Some(LengthUnit::Foot));
    assert_eq!(unit_from_factor(1.0), Some(LengthUnit::Metre));
    assert_eq!(unit_from_factor(1000.0), None);
}

#[test]
fn short_geokey_directory_is_an_error() {
    assert!(from_geokeys("LAS", &[1, 0], None, None).is_err());
    let dir: Vec<u8> = [1u16, 1, 0, 5, 3076, 0, 1, 9001]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    assert!(
        from_geokeys("LAS", &dir, None, None)
            .expect_err("5 keys claimed")
            .to_string()
            .contains("says 5 keys")
    );
}
